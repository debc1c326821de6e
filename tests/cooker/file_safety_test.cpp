// The tools' file-safety rules (io.h, issue 15): reads take regular files within a size limit;
// an output is never an input, another output or something that is not a regular file; a write
// interrupted by SIGINT/SIGTERM leaves no temporary, and a killed run's leftover is removed by the
// next write of the same file. Also how names are printed (printable.h).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cooker/printable.h"

namespace lightpatch::test {
namespace {

namespace fs = std::filesystem;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
    ADD_FAILURE() << "no error";
  } catch (const cooker::CookError& e) {
    return e.what();
  }
  return {};
}

#define EXPECT_HAS(text, word)                               \
  EXPECT_NE(std::string(text).find(word), std::string::npos) \
      << "'" << (word) << "' not in: " << (text)

std::string text_of(const std::string& path) {
  const std::vector<std::uint8_t> b = read_bytes(path);
  return std::string(b.begin(), b.end());
}

// A pid no process has: a child that has exited and been reaped.
pid_t dead_pid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return pid;
}

TEST(FileSafety, ReadsTakeRegularFilesWithinTheLimit) {
  ScratchDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Refused at once: no writer is waited for.
  EXPECT_HAS(error_of([&] { cooker::read_file(fifo); }), "it is a FIFO, not a regular file");
  EXPECT_HAS(error_of([&] { cooker::read_file("/dev/zero"); }),
             "'/dev/zero': it is a character device, not a regular file");
  EXPECT_HAS(error_of([&] { cooker::read_file(dir.path().string()); }), "it is a directory");

  const std::string big = dir.file("big.json");
  write_text(big, std::string(3000, ' '));
  const uint64_t saved = cooker::input_size_limit();
  cooker::set_input_size_limit(2048);
  const std::string m = error_of([&] { cooker::read_file(big); });
  cooker::set_input_size_limit(saved);
  EXPECT_HAS(m, "3000 bytes, over the input size limit of 2048 bytes");
  EXPECT_HAS(m, "--max-input-mb N raises it");
  EXPECT_EQ(cooker::read_file(big).size(), 3000u);
}

TEST(FileSafety, AnOutputIsNeverAnInputOrAnotherOutput) {
  ScratchDir dir;
  const std::string scene = dir.file("scene.gltf");
  write_text(scene, "{}");
  fs::create_hard_link(scene, dir.file("hard.gltf"));
  fs::create_symlink("scene.gltf", dir.path() / "soft.gltf");
  const std::string out = dir.file("out.lpk");
  EXPECT_NO_THROW(cooker::check_command_files({scene, ""}, {out, dir.file("report.json"), ""}));
  const std::vector<std::string> same_as_scene = {
      scene, dir.file("hard.gltf"), dir.file("soft.gltf"),
      (dir.path() / "." / "x" / ".." / "scene.gltf").string()};
  for (const std::string& alias : same_as_scene) {
    const std::string m = error_of([&] { cooker::check_command_files({scene}, {out, alias}); });
    EXPECT_HAS(m, "refusing to write");
    EXPECT_HAS(m, "it is the input '" + scene + "' of the same command");
  }
  // Two outputs naming one file, one of them not yet existing.
  EXPECT_HAS(error_of([&] {
               cooker::check_command_files({scene}, {out, dir.file("./out.lpk")});
             }),
             "it is also the output '" + out + "'");
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_HAS(error_of([&] { cooker::check_command_files({scene}, {fifo}); }),
             "it exists and is a FIFO, not a regular file");
  EXPECT_HAS(error_of([&] { cooker::check_command_files({scene}, {"/dev/null"}); }),
             "'/dev/null': it exists and is a character device");
}

TEST(FileSafety, WritesNeverReplaceWhatIsNotARegularFile) {
  ScratchDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_HAS(error_of([&] { cooker::write_file_atomic(fifo, "x", 1); }), "it exists and is a FIFO");
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_HAS(error_of([&] { cooker::write_file_atomic("/dev/null", "x", 1); }),
             "it exists and is a character device");
  // A link to a regular file: the file is replaced, the link stays a link.
  write_text(dir.file("target.txt"), "old");
  fs::create_symlink("target.txt", dir.path() / "link.txt");
  cooker::write_file_atomic(dir.file("link.txt"), "new", 3);
  EXPECT_TRUE(fs::is_symlink(dir.path() / "link.txt"));
  EXPECT_EQ(text_of(dir.file("target.txt")), "new");
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"fifo", "link.txt", "target.txt"}));
}

TEST(FileSafety, LeftoversOfKilledRunsAreRemovedByTheNextWrite) {
  ScratchDir dir;
  const std::string out = dir.file("scene.lpk");
  const std::string dead =
      "scene.lpk" + std::string(cooker::kTemporaryMarker) + std::to_string(dead_pid()) + "-Ab3dEf";
  // This process is alive: its temporaries may be in use and stay.
  const std::string live =
      "scene.lpk" + std::string(cooker::kTemporaryMarker) + std::to_string(::getpid()) + "-Zz9yX8";
  const std::string other =
      "other.lpk" + std::string(cooker::kTemporaryMarker) + std::to_string(dead_pid()) + "-Ab3dEf";
  for (const std::string& name : {dead, live, other}) write_text(dir.file(name), "partial");
  cooker::write_file_atomic(out, "pack", 4);
  std::vector<std::string> kept = {live, other, "scene.lpk"};
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(dir.entries(), kept);
}

// A child writes part of `out` through an AtomicFile, tells where its temporary is, and waits
// for `sig`; the parent checks that the signal removed the temporary and killed the child.
void interrupt_a_write(int sig) {
  ScratchDir dir;
  const std::string out = dir.file("map.pfm");
  write_text(out, "old map");
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(pipe_fds[0]);
    cooker::install_temporary_cleanup();
    cooker::AtomicFile file(out);
    file.write("half a map", 10);
    const std::string& temp = file.temporary_path();
    if (::write(pipe_fds[1], temp.data(), temp.size()) < 0) ::_exit(3);
    ::close(pipe_fds[1]);
    for (;;) ::pause();
  }
  ::close(pipe_fds[1]);
  std::string temp;
  char buffer[4096];
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0;) temp.append(buffer, n);
  ::close(pipe_fds[0]);
  ASSERT_TRUE(fs::exists(temp)) << temp;
  EXPECT_NE(temp.find("map.pfm" + std::string(cooker::kTemporaryMarker) + std::to_string(pid)),
            std::string::npos)
      << temp;
  ASSERT_EQ(::kill(pid, sig), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_EQ(text_of(out), "old map");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"map.pfm"});
}

TEST(FileSafety, SigtermDuringAWriteLeavesNoTemporary) {
  interrupt_a_write(SIGTERM);
}

TEST(FileSafety, SigintDuringAWriteLeavesNoTemporary) {
  interrupt_a_write(SIGINT);
}

TEST(Printable, EscapesControlsAndCutsLongText) {
  EXPECT_EQ(cooker::printable("candle_3"), "candle_3");
  EXPECT_EQ(cooker::printable("caf\xC3\xA9 \xE2\x82\xAC"), "caf\xC3\xA9 \xE2\x82\xAC");
  EXPECT_EQ(cooker::printable("a\x1B[31mb\nc\td\\"), "a\\x1B[31mb\\nc\\td\\\\");
  EXPECT_EQ(cooker::printable("\xC2\x9B"
                              "2J"),
            "\\u009B2J");                                           // C1 CSI
  EXPECT_EQ(cooker::printable("x\xE2\x80\xAEy"), "x\\u202Ey");      // right-to-left override
  EXPECT_EQ(cooker::printable("\xFF\xC0\xAF"), "\\xFF\\xC0\\xAF");  // not UTF-8
  EXPECT_EQ(cooker::printable(std::string("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(cooker::printable(std::string(1000, 'n'), 10), "nnnnnnnnnn... (1000 bytes)");
  EXPECT_EQ(cooker::quote("lamp"), "'lamp'");
}

}  // namespace
}  // namespace lightpatch::test
