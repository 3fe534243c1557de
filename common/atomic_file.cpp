#include "common/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <thread>

namespace vobb {

namespace {

// Writes all of `content` to fd; false with errno set on failure.
bool write_all(int fd, const std::string& content) {
  size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  return true;
}

// A name write_file_atomic gives its temporary files: ".vobb-<pid>-<n>.tmp", both decimal.
bool is_temporary_name(const std::string& name) {
  const std::string head = ".vobb-", tail = ".tmp";
  if (name.size() <= head.size() + tail.size() || name.compare(0, head.size(), head) != 0 ||
      name.compare(name.size() - tail.size(), tail.size(), tail) != 0)
    return false;
  const std::string middle = name.substr(head.size(), name.size() - head.size() - tail.size());
  const size_t dash = middle.find('-');
  if (dash == 0 || dash == std::string::npos || dash + 1 == middle.size()) return false;
  for (size_t i = 0; i < middle.size(); ++i)
    if (i != dash && (middle[i] < '0' || middle[i] > '9')) return false;
  return true;
}

}  // namespace

Status write_file_atomic(const std::string& path, const std::string& content) {
  auto fail = [&](const std::string& why) {
    return Status::error(path + ": cannot write: " + why);
  };
  // Something that is not a regular file (a device such as /dev/null, a pipe), reached
  // directly or through links (/dev/stdout), is written to in place: it cannot be replaced,
  // and must not be. It is opened by the path given, as the kernel resolves it: a pipe's link
  // in /proc names no folder a file could be made in.
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) return fail("is a directory");
    // A named pipe that no process reads would block the open forever. It is opened without
    // blocking, which fails (ENXIO) while no reader has it open; a reader started beside the
    // run gets kPipeReaderWaitSeconds to open it. Once open it is written with blocking.
    int fd = -1;
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
      fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK);
      if (fd >= 0 || errno != ENXIO || !S_ISFIFO(st.st_mode) ||
          std::chrono::steady_clock::now() - start > std::chrono::seconds(kPipeReaderWaitSeconds))
        break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (fd < 0)
      return fail(errno == ENXIO && S_ISFIFO(st.st_mode)
                      ? "a named pipe that no process opened for reading within " +
                            std::to_string(kPipeReaderWaitSeconds) + " s"
                      : std::strerror(errno));
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      return fail(why);
    }
    const bool ok = write_all(fd, content);
    const std::string why = std::strerror(errno);
    if (::close(fd) != 0 && ok) return fail(std::strerror(errno));
    return ok ? Status::ok() : fail(why);
  }
  // A symbolic link to a regular file, or to nothing yet, is followed: its target is
  // replaced, the link stays.
  std::string target;
  if (Status s = output_target(path, &target); !s) return s;
  // The temporary file's name is short whatever the target's (a name of 255 bytes is valid).
  // Its lock, held until it is closed, tells remove_stray_temporaries that it is being written.
  // A name taken already (a killed run's file under a pid used again) is passed over.
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path dir = std::filesystem::path(target).parent_path();
  std::string tmp;
  int fd = -1;
  for (int tries = 0; fd < 0 && tries < 64; ++tries) {
    tmp = (dir / (".vobb-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tmp"))
              .string();
    fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) return fail(std::strerror(errno));
  ::flock(fd, LOCK_EX);
  if (!write_all(fd, content)) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    ::unlink(tmp.c_str());
    return fail(why);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    return fail(why);
  }
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    return fail(why);
  }
  return Status::ok();
}

Status output_target(const std::string& path, std::string* target) {
  namespace fs = std::filesystem;
  fs::path at(path);
  // Linux follows at most 40 links in one path (MAXSYMLINKS); a longer chain is refused too.
  for (int hops = 0; hops <= 40; ++hops) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(at, ec))) {
      *target = at.string();
      return Status::ok();
    }
    const fs::path next = fs::read_symlink(at, ec);
    if (ec) return Status::error(path + ": cannot follow the link: " + ec.message());
    at = next.is_absolute() ? next : at.parent_path() / next;
  }
  return Status::error(path + ": cannot follow the link: a loop or more than 40 links");
}

size_t remove_stray_temporaries(const std::string& folder) {
  namespace fs = std::filesystem;
  size_t removed = 0;
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (!is_temporary_name(it->path().filename().string())) continue;
    std::error_code type_ec;
    if (it->is_symlink(type_ec) || !it->is_regular_file(type_ec)) continue;
    const auto written = fs::last_write_time(it->path(), type_ec);
    if (type_ec || now - written < std::chrono::seconds(kStrayAgeSeconds)) continue;
    const int fd = ::open(it->path().c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) continue;
    // Unlocked: no writer holds it open (a writer locks it from its creation to its close).
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::unlink(it->path().c_str()) == 0) ++removed;
    ::close(fd);
  }
  return removed;
}

Status check_folder_takes_files(const std::string& what, const std::string& dir) {
  const std::filesystem::path probe =
      std::filesystem::path(dir) / (".vobb-" + std::to_string(::getpid()) + "-probe.tmp");
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return Status::error(what + ": cannot write in " + dir + ": " + std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
  return Status::ok();
}

std::string not_a_folder(const std::string& dir) {
  std::error_code ec;
  return std::filesystem::exists(dir, ec) ? dir + " is not a folder" : "no such folder " + dir;
}

Status make_checkpoint_folder(const std::string& what, const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // The folder is made, its parent is not: a mistyped parent is refused as `-o` refuses it,
  // not made into a chain of folders.
  fs::path own = fs::path(folder).lexically_normal();
  if (!own.has_filename()) own = own.parent_path();  // "ck/" names ck
  fs::path parent = own.parent_path();
  if (parent.empty()) parent = ".";
  if (!fs::is_directory(folder, ec) && !fs::is_directory(parent, ec))
    return Status::error(what + ": " + not_a_folder(parent.string()));
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec))
    return Status::error(what + ": " + folder + " is not a folder");
  fs::create_directory(folder, ec);
  if (ec) return Status::error(what + ": cannot make the checkpoint folder: " + ec.message());
  // A folder such as /sys/kernel exists and takes no file.
  if (Status s = check_folder_takes_files(what, folder); !s) return s;
  remove_stray_temporaries(
      folder);  // a run killed while it wrote a checkpoint left its temporary file
  return Status::ok();
}

}  // namespace vobb
