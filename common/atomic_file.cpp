#include "common/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

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

}  // namespace

Status write_file_atomic(const std::string& path, const std::string& content) {
  auto fail = [&](const std::string& why) { return Status::error(path + ": cannot write: " + why); };
  // Something that is not a regular file (a device such as /dev/null, a pipe), reached
  // directly or through links (/dev/stdout), is written to in place: it cannot be replaced,
  // and must not be. It is opened by the path given, as the kernel resolves it: a pipe's link
  // in /proc names no folder a file could be made in.
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) return fail("is a directory");
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return fail(std::strerror(errno));
    const bool ok = write_all(fd, content);
    const std::string why = std::strerror(errno);
    if (::close(fd) != 0 && ok) return fail(std::strerror(errno));
    return ok ? Status::ok() : fail(why);
  }
  // A symbolic link to a regular file, or to nothing yet, is followed: its target is
  // replaced, the link stays.
  std::error_code ec;
  std::string target = path;
  if (std::filesystem::is_symlink(std::filesystem::symlink_status(path, ec))) {
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(path, ec);
    if (ec) return fail(ec.message());
    target = resolved.string();
  }
  // The temporary file's name is short whatever the target's (a name of 255 bytes is valid).
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path dir = std::filesystem::path(target).parent_path();
  const std::string tmp = (dir / (".vobb-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tmp")).string();
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return fail(std::strerror(errno));
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

}  // namespace vobb
