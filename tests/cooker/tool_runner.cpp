#include "tool_runner.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

#ifndef LIGHTPATCH_TOOL
#error "tests/cooker/CMakeLists.txt passes the path of build/bin/lightpatch as LIGHTPATCH_TOOL"
#endif

namespace lightpatch::test {

ToolRun run_tool(const std::vector<std::string>& args) {
  std::vector<std::string> argv_strings = {LIGHTPATCH_TOOL};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0 || ::pipe(err_pipe) != 0) throw std::runtime_error("test: pipe");
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("test: fork");
  if (pid == 0) {
    ::dup2(out_pipe[1], 1);
    ::dup2(err_pipe[1], 2);
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    ::close(out_pipe[1]);
    ::close(err_pipe[1]);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  ToolRun r;
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&r.out, &r.err};
  int open_fds = 2;
  while (open_fds > 0) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buffer[4096];
      const ssize_t n = ::read(fds[i].fd, buffer, sizeof(buffer));
      if (n > 0) {
        sinks[i]->append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        ::close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

std::string describe(const std::vector<std::string>& args, const ToolRun& r) {
  std::string s = "lightpatch";
  for (const auto& a : args) s += " " + a;
  return s + "\nexit " + std::to_string(r.code) + "\nstdout: " + r.out + "\nstderr: " + r.err;
}

const std::vector<std::string> kFast = {"--quality", "draft", "--lightmap-size", "32", "--quiet"};

std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

ToolRun expect_success(const std::vector<std::string>& args) {
  const ToolRun r = run_tool(args);
  EXPECT_EQ(r.code, 0) << describe(args, r);
  return r;
}

}  // namespace lightpatch::test
