// lightpatch-inn's command line: `generate --help` and `play --help` print every option the verb
// parses and exit 0; a usage error exits 2 with the usage on stderr.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <string>
#include <vector>

namespace lightpatch::inn {
namespace {

struct Ran {
  int rc = -1;
  std::string out;  // stdout only
};

Ran run_inn(const std::string& args) {
  Ran r;
  const std::string command =
      std::string("\"") + LIGHTPATCH_INN_BIN + "\" " + args + " 2>/dev/null";
  std::FILE* p = popen(command.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

void expect_documents(const std::string& verb, const std::vector<std::string>& options) {
  const Ran r = run_inn(verb + " --help");
  EXPECT_EQ(r.rc, 0) << verb << " --help";
  for (const std::string& o : options) {
    EXPECT_NE(r.out.find("  " + o), std::string::npos) << verb << " --help lacks " << o << ":\n"
                                                       << r.out;
  }
}

TEST(InnCli, GenerateHelpDocumentsEveryOption) {
  expect_documents("generate", {"-o, --output", "--draco", "--scale", "--seed", "-h, --help"});
}

TEST(InnCli, PlayHelpDocumentsEveryOption) {
  expect_documents("play",
                   {"--window", "--headless", "--script", "--out", "--scene", "--pack", "--size",
                    "--budget", "--exposure", "--drift-ulps", "--frames", "--cpu", "-h, --help"});
}

TEST(InnCli, UsageErrorsExitTwoAndPrintNothingOnStdout) {
  for (const char* args :
       {"", "bogus", "generate --bogus", "generate", "generate --scale huge -o x", "play --bogus",
        "play --size 3x3", "play --script default"}) {
    const Ran r = run_inn(args);
    EXPECT_EQ(r.rc, 2) << "lightpatch-inn " << args;
    EXPECT_TRUE(r.out.empty()) << "lightpatch-inn " << args << " wrote to stdout:\n" << r.out;
  }
  const Ran top = run_inn("--help");
  EXPECT_EQ(top.rc, 0);
  EXPECT_NE(top.out.find("lightpatch-inn VERB --help"), std::string::npos) << top.out;
}

}  // namespace
}  // namespace lightpatch::inn
