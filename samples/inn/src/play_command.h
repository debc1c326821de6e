// `lightpatch-inn play`: argument parsing and dispatch to the windowed game or the headless
// scripted run.
#pragma once

namespace lightpatch::inn {

// argv[0] is "play". Returns the process exit status.
int play_command(int argc, char** argv);

}  // namespace lightpatch::inn
