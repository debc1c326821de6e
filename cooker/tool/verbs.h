// The `lightpatch` tool's verbs. Each takes the arguments after the verb name, prints a clear
// error and returns non-zero on bad input, and never leaves a partial output file behind.
#pragma once

namespace lightpatch::tool {

struct Args;

int verb_cook(Args& args);        // cook_verbs.cpp
int verb_bake_state(Args& args);  // cook_verbs.cpp
int verb_info(Args& args);        // pack_verbs.cpp
int verb_verify(Args& args);      // pack_verbs.cpp
int verb_recompose(Args& args);   // pack_verbs.cpp
int verb_preview(Args& args);     // pack_verbs.cpp
int verb_bench(Args& args);       // bench_verb.cpp
int verb_accuracy(Args& args);    // accuracy_verb.cpp
int verb_plan(Args& args);        // farm_verbs.cpp
int verb_cook_job(Args& args);    // farm_verbs.cpp
int verb_jobs(Args& args);        // farm_verbs.cpp
int verb_assemble(Args& args);    // farm_verbs.cpp

}  // namespace lightpatch::tool
