// The windowed game: `lightpatch-inn play` walks the inn in an X11 window.
//   W A S D walk, Shift runs, mouse or arrow keys look, E uses what is in front of you (light or
//   snuff a flame, take an item, place a carried item on the altar), Esc quits.
// Returns 0 on a normal exit, 1 on a runtime or GL error.
#pragma once

#include "play_session.h"

namespace lightpatch::inn {

int run_interactive(PlaySession& session, const PlayOptions& options);

}  // namespace lightpatch::inn
