// libFuzzer target: the scene-state reader (cooker/src/state_spec.cpp), as one JSON state and as
// a --states file of one state per line. Any input must end in states or a CookError; anything
// else (a crash, a sanitizer report, another exception) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/state_spec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lightpatch::cooker;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)parse_state_json(text, "fuzz");
  } catch (const CookError&) {
    // A clear error is the right answer to bad input.
  }
  try {
    (void)parse_states_jsonl(text, "fuzz");
  } catch (const CookError&) {
  }
  return 0;
}
