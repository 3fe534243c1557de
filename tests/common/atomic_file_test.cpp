#include "common/atomic_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "test_common.h"

namespace vobb {
namespace {

using test::slurp;

// The content replaces the file whole, and nothing else is left in the folder.
TEST(WriteFileAtomic, ReplacesTheFileAndLeavesNoTemporary) {
  const std::filesystem::path dir = test::temp_path("atomic_dir");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directory(dir);
  const std::string path = (dir / "out.txt").string();
  ASSERT_TRUE(write_file_atomic(path, "first"));
  ASSERT_TRUE(write_file_atomic(path, "second"));
  EXPECT_EQ(slurp(path), "second");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                          std::filesystem::directory_iterator()),
            1);
  // A name of 255 bytes (NAME_MAX) is valid: the temporary file's own name must not depend on it.
  const std::string longest = (dir / std::string(255, 'n')).string();
  EXPECT_TRUE(write_file_atomic(longest, "long")) << "a valid name refused";
  EXPECT_EQ(slurp(longest), "long");
  // A folder is refused, and left as it was.
  EXPECT_FALSE(write_file_atomic(dir.string(), "x"));
  EXPECT_TRUE(std::filesystem::is_directory(dir));
  std::filesystem::remove_all(dir);
}

// A symbolic link is followed: the file it points to gets the content, the link stays a link.
TEST(WriteFileAtomic, FollowsASymbolicLink) {
  const std::filesystem::path dir = test::temp_path("atomic_link");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directory(dir);
  const std::filesystem::path target = dir / "target.txt", link = dir / "link.txt";
  ASSERT_TRUE(write_file_atomic(target.string(), "old"));
  std::filesystem::create_symlink(target.filename(), link);
  ASSERT_TRUE(write_file_atomic(link.string(), "new"));
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(link)));
  EXPECT_EQ(slurp(target.string()), "new");
  std::filesystem::remove_all(dir);
}

// A link to a file that is not there yet, through a second link: the chain is followed to its
// end, which is written, and both links stay links. A loop of links is refused, and left.
TEST(WriteFileAtomic, FollowsAChainOfLinksToAFileNotThereYet) {
  const std::filesystem::path dir = test::temp_path("atomic_chain");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "sub");
  std::filesystem::create_symlink("sub/inner.txt", dir / "outer.txt");
  std::filesystem::create_symlink("target.txt", dir / "sub" / "inner.txt");  // relative to sub/
  ASSERT_TRUE(write_file_atomic((dir / "outer.txt").string(), "chained"));
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(dir / "outer.txt")));
  EXPECT_TRUE(
      std::filesystem::is_symlink(std::filesystem::symlink_status(dir / "sub" / "inner.txt")));
  EXPECT_EQ(slurp((dir / "sub" / "target.txt").string()), "chained");
  std::string target;
  ASSERT_TRUE(output_target((dir / "outer.txt").string(), &target));
  EXPECT_EQ(target, (dir / "sub" / "target.txt").string());
  std::filesystem::create_symlink("loop_b", dir / "loop_a");
  std::filesystem::create_symlink("loop_a", dir / "loop_b");
  const Status s = write_file_atomic((dir / "loop_a").string(), "x");
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("loop"), std::string::npos) << s.message();
  EXPECT_TRUE(std::filesystem::is_symlink(std::filesystem::symlink_status(dir / "loop_a")));
  std::filesystem::remove_all(dir);
}

// A named pipe cannot be replaced by a file: it is written to in place (its reader gets the
// content) and stays a pipe. The reader opens first, without blocking, so that a failure
// cannot hang the test.
TEST(WriteFileAtomic, WritesIntoAPipeInPlace) {
  const std::string fifo = test::temp_path("atomic_fifo");
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  EXPECT_TRUE(write_file_atomic(fifo, "through the pipe"));  // fits the pipe's buffer
  char buf[64] = {};
  const ssize_t n = ::read(reader, buf, sizeof buf - 1);
  ::close(reader);
  EXPECT_EQ(std::string(buf, n > 0 ? n : 0), "through the pipe");
  struct stat st;
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  std::filesystem::remove(fifo);
}

// A named pipe that no process reads: the open would block forever; it is refused after
// kPipeReaderWaitSeconds instead, in one line, and the pipe stays. A reader that opens it a
// moment after the write began gets the content.
TEST(WriteFileAtomic, RefusesANamedPipeThatNoProcessReads) {
  const std::string fifo = test::temp_path("atomic_fifo_unread");
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = write_file_atomic(fifo, "nobody listens");
  EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::seconds(kPipeReaderWaitSeconds));
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("a named pipe that no process opened for reading within 5 s"),
            std::string::npos)
      << s.message();
  std::string got;
  std::thread late_reader([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    std::ifstream in(fifo);
    std::getline(in, got);
  });
  EXPECT_TRUE(write_file_atomic(fifo, "a late reader\n"));
  late_reader.join();
  EXPECT_EQ(got, "a late reader");
  struct stat st;
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  std::filesystem::remove(fifo);
}

// An anonymous pipe reached through its link in /proc, as `-o /dev/stdout` reaches the pipe
// of `vobb build ... | cat`: the link resolves to "pipe:[N]", in no folder a file could be
// made in, so it must be opened as given and written in place.
TEST(WriteFileAtomic, WritesIntoAPipeThroughItsProcLink) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const std::string link = "/proc/self/fd/" + std::to_string(fds[1]);
  EXPECT_TRUE(write_file_atomic(link, "down the pipe"));  // fits the pipe's buffer
  ::close(fds[1]);
  char buf[64] = {};
  const ssize_t n = ::read(fds[0], buf, sizeof buf - 1);
  ::close(fds[0]);
  EXPECT_EQ(std::string(buf, n > 0 ? n : 0), "down the pipe");
}

// A run killed mid-write leaves ".vobb-<pid>-<n>.tmp" beside its target. Those go that no
// writer holds (locks) and that were last written over kStrayAgeSeconds ago, whatever the pid
// (this process's own too: a pid used again); a file being written (locked, as
// write_file_atomic holds its own), one written just now, names that merely look alike and a
// folder of that name stay.
TEST(RemoveStrayTemporaries, RemovesOnlyUnheldOldFilesOfThatName) {
  namespace fs = std::filesystem;
  const fs::path dir = test::temp_path("stray_dir");
  fs::remove_all(dir);
  fs::create_directory(dir);
  const std::string mine = std::to_string(::getpid());
  const std::vector<std::string> gone = {".vobb-12345-0.tmp", ".vobb-" + mine + "-17.tmp"};
  const std::string held = ".vobb-777-1.tmp", fresh = ".vobb-778-2.tmp";
  const std::vector<std::string> alike = {
      ".vobb-12345.tmp",  ".vobb--0.tmp",       ".vobb-12345-.tmp", ".vobb-12345-1x.tmp",
      "vobb-12345-0.tmp", ".vobb-12345-0.tmpx", "state.json"};
  const auto old = fs::file_time_type::clock::now() - std::chrono::seconds(2 * kStrayAgeSeconds);
  // Made plainly (write_file_atomic's own temporaries are named like this process's file).
  for (const std::string& name : gone) std::ofstream(dir / name) << "half";
  for (const std::string& name : alike) std::ofstream(dir / name) << "keep";
  std::ofstream(dir / held) << "keep";
  std::ofstream(dir / fresh) << "keep";
  for (const std::string& name : gone) fs::last_write_time(dir / name, old);
  for (const std::string& name : alike) fs::last_write_time(dir / name, old);
  fs::last_write_time(dir / held, old);
  fs::create_directory(dir / ".vobb-12345-9.tmp");
  const int writer = ::open((dir / held).c_str(), O_WRONLY | O_CLOEXEC);
  ASSERT_GE(writer, 0);
  ASSERT_EQ(::flock(writer, LOCK_EX), 0);
  EXPECT_EQ(remove_stray_temporaries(dir.string()), gone.size());
  for (const std::string& name : gone) EXPECT_FALSE(fs::exists(dir / name)) << name;
  for (const std::string& name : alike) EXPECT_EQ(slurp((dir / name).string()), "keep") << name;
  EXPECT_EQ(slurp((dir / held).string()), "keep");
  EXPECT_EQ(slurp((dir / fresh).string()), "keep");
  EXPECT_TRUE(fs::is_directory(dir / ".vobb-12345-9.tmp"));
  // Once its writer is gone, the held file goes too.
  ::close(writer);
  EXPECT_EQ(remove_stray_temporaries(dir.string()), 1u);
  EXPECT_FALSE(fs::exists(dir / held));
  EXPECT_EQ(remove_stray_temporaries(dir.string()), 0u);  // nothing left to remove
  EXPECT_EQ(remove_stray_temporaries((dir / "absent").string()), 0u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vobb
