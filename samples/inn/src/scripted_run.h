// The headless scripted run: `lightpatch-inn play --headless --script default --out DIR` plays
// the generator's scenario (OUT.scenario.json) step by step on a surfaceless context, with the
// same game rules and flicker as the window, and writes to DIR:
//   NN_<step>.png  a screenshot after each step has landed (plus a few frames of flicker);
//   frames.csv     one row per frame (see FrameRecord);
//   steps.csv      one row per step: when it was made, when it landed, its latency bound, and the
//                  light-map brightness around the light it switched, before and after;
//   summary.json   light-map size, budget, runtime memory, frame-time means.
// Frame times are measured with glFinish() after the recomposition and after drawing, so that
// the recomposition's share is its own (llvmpipe draws when flushed).
// Returns 0 when every step landed within its bound with no GL error; 1 otherwise.
#pragma once

#include "play_session.h"

namespace lightpatch::inn {

int run_scripted(PlaySession& session, const PlayOptions& options);

}  // namespace lightpatch::inn
