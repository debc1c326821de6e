// Every option spelling a verb's --help documents is one the verb accepts: for each verb, each
// spelling of each option in its "options:" list (aliases such as -o and --output included) is
// passed, with a value of the documented kind, next to the verb's required arguments and an input
// that does not exist. The verb must then fail on the missing input (exit 1), never on its
// arguments (exit 2, "unexpected argument"); a spelling only the help knows is caught here.
#include <gtest/gtest.h>

#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "tool_runner.h"

namespace lightpatch::test {
namespace {

struct Option {
  std::vector<std::string> spellings;  // "-o", "--output"
  std::string value;                   // placeholder ("MAP.pfm", "N", "cpu|gles"), empty: a flag
};

// The options of a verb's help text: lines "  -x, --name VALUE   description" after "options:".
std::vector<Option> documented_options(const std::string& help) {
  std::vector<Option> out;
  std::istringstream in(help);
  std::string line;
  bool in_options = false;
  while (std::getline(in, line)) {
    if (line == "options:") in_options = true;
    if (!in_options || line.rfind("  -", 0) != 0) continue;
    std::string spec = line.substr(2, line.find("  ", 2) - 2);  // up to the description
    Option o;
    for (size_t start = 0; start < spec.size();) {
      size_t comma = spec.find(", ", start);
      std::string part =
          spec.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      const size_t space = part.find(' ');
      if (space != std::string::npos) {
        o.value = part.substr(space + 1);
        part = part.substr(0, space);
      }
      o.spellings.push_back(part);
      start = comma == std::string::npos ? spec.size() : comma + 2;
    }
    out.push_back(o);
  }
  return out;
}

// The usage line's required arguments: positionals and options outside [...].
std::vector<std::string> required_arguments(const std::string& help, const ScratchDir& dir,
                                            std::vector<std::string>* option_names) {
  const std::string usage = help.substr(0, help.find('\n'));
  std::string outside;
  int depth = 0;
  for (char c : usage) {
    depth += c == '[';
    if (depth == 0) outside += c;
    depth -= c == ']';
  }
  std::istringstream words(outside);
  std::string w;
  std::vector<std::string> args;
  words >> w >> w >> w;  // "usage:", "lightpatch", the verb
  while (words >> w) {
    if (w[0] == '-') {
      option_names->push_back(w);
      args.push_back(w);
      words >> w;
    }
    args.push_back(dir.file("missing_" + w));  // a file that does not exist
  }
  return args;
}

// A value of the documented kind: the first of alternatives (the help's, or those a usage line
// of `usages` gives this option), a number, or a scratch path.
std::string value_for(const std::string& placeholder, const ScratchDir& dir,
                      const std::string& usages = "", const std::string& spelling = "") {
  std::smatch in_usage;
  if (!spelling.empty() &&
      std::regex_search(usages, in_usage, std::regex("\\[" + spelling + " ([^\\[\\] ]+)\\]")) &&
      in_usage[1].str().find('|') != std::string::npos) {
    return in_usage[1].str().substr(0, in_usage[1].str().find('|'));
  }
  if (placeholder.find('|') != std::string::npos)
    return placeholder.substr(0, placeholder.find('|'));
  if (placeholder == "Q") return "draft";
  if (placeholder == "N" || placeholder == "K" || placeholder == "F") return "8";
  return dir.file("value_" + placeholder);
}

TEST(CliOptions, EveryDocumentedSpellingIsAccepted) {
  ScratchDir dir;
  const ToolRun top = run_tool({"--help"});
  ASSERT_EQ(top.code, 0);
  std::istringstream verbs(top.out.substr(top.out.find("verbs:")));
  std::string line;
  int checked = 0;
  while (std::getline(verbs, line)) {
    const std::string prefix = "  lightpatch ";
    if (line.rfind(prefix, 0) != 0) continue;
    const std::string verb =
        line.substr(prefix.size(), line.find(' ', prefix.size()) - prefix.size());
    const ToolRun help = run_tool({verb, "--help"});
    ASSERT_EQ(help.code, 0) << verb;
    std::vector<std::string> required_names;
    const std::vector<std::string> required = required_arguments(help.out, dir, &required_names);
    const std::vector<Option> options = documented_options(help.out);
    const std::string usage = help.out.substr(0, help.out.find('\n'));
    for (const Option& o : options) {
      for (const std::string& spelling : o.spellings) {
        // The verb's required arguments, minus any that this option is a spelling of.
        std::vector<std::string> args = {verb};
        for (size_t i = 0; i < required.size(); ++i) {
          bool same = false;
          for (const std::string& s : o.spellings) same |= required[i] == s;
          if (same) {
            ++i;  // and its value
            continue;
          }
          args.push_back(required[i]);
        }
        // An option nested in another's brackets ("[--runtime-csv OUT.csv [--gles]]") needs it.
        std::smatch parent;
        const std::regex nested("\\[(--[a-z-]+) ([^\\[\\] ]+) \\[" + o.spellings.back() + "\\b");
        if (std::regex_search(usage, parent, nested)) {
          args.push_back(parent[1]);
          args.push_back(value_for(parent[2], dir));
        }
        args.push_back(spelling);
        if (!o.value.empty()) args.push_back(value_for(o.value, dir, top.out, o.spellings.back()));
        const ToolRun r = run_tool(args);
        // Exit 1: the missing input. Exit 2 only when the option was recognized and its number
        // refused ("--denoise takes an integer in [0, 3]"), never "unexpected argument".
        const bool value_refused = r.code == 2 && r.err.find(spelling) != std::string::npos;
        EXPECT_TRUE(r.code == 1 || value_refused) << describe(args, r);
        EXPECT_EQ(r.err.find("unexpected argument"), std::string::npos) << describe(args, r);
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 40);              // cook alone documents 15
  EXPECT_TRUE(dir.entries().empty());  // nothing written
}

}  // namespace
}  // namespace lightpatch::test
