// Formats other than OFF/OBJ/PLY/STL, through Debian's assimp. Its `ai_real` is float, so
// coordinates arrive rounded to float32; the caller is told (`single_precision`).
//
// Assimp's importers are not hardened against malformed files: a few dozen damaged bytes make
// some of them (AC3D, ASE, NFF, RAW, X, COLLADA, SMD in assimp 5.2) fail an assertion, crash or
// loop forever. So the import runs in a child process (fork), under a CPU-time limit and the
// address-space cap below, with its stdout and stderr sent to /dev/null; the mesh comes back
// through a pipe. A crash or a loop then ends in a one-line refusal instead of taking vobb down.
#include "common/io/assimp_reader.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <assimp/Importer.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>

#include "common/io/mesh_io.h"

namespace vobb {
namespace {

// Some formats describe geometry procedurally (NFF's "pp 99999999 99999999" is 21 bytes and
// asks for 10^16 vertices), so assimp's memory is not bounded by the file's size. While it
// reads, the process's address space is capped at what it uses now plus an allowance
// (1 GiB + 256 bytes per byte of file: text formats hold a vertex in about 30 bytes and
// assimp keeps it in 12, and compressed formats rarely expand 100-fold), so a bomb ends in
// std::bad_alloc, which assimp reports as a failed read, instead of exhausting the machine.
class AddressSpaceCap {
 public:
  explicit AddressSpaceCap(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || ::getrlimit(RLIMIT_AS, &saved_) != 0) return;
    unsigned long pages = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%lu", &pages) != 1) pages = 0;
      std::fclose(f);
    }
    if (pages == 0) return;
    const double used = static_cast<double>(pages) * static_cast<double>(::sysconf(_SC_PAGESIZE));
    allowance_ = (1u << 30) + 256.0 * static_cast<double>(st.st_size);
    const double cap = used + allowance_;
    if (saved_.rlim_cur != RLIM_INFINITY && static_cast<double>(saved_.rlim_cur) <= cap) return;
    struct rlimit lowered = saved_;
    lowered.rlim_cur = static_cast<rlim_t>(cap);
    active_ = ::setrlimit(RLIMIT_AS, &lowered) == 0;
  }
  ~AddressSpaceCap() {
    if (active_) ::setrlimit(RLIMIT_AS, &saved_);
  }
  double allowance_gib() const { return allowance_ / (1u << 30); }

 private:
  struct rlimit saved_ {};
  bool active_ = false;
  double allowance_ = 0;
};

// Assimp opens the files a scene names itself (a LightWave scene's objects, an OBJ's
// materials); like vobb's own reader it is given regular files only: a pipe or a device
// there would block it or feed it without end.
class RegularFilesOnly : public Assimp::DefaultIOSystem {
 public:
  bool Exists(const char* file) const override {
    return regular(file) && DefaultIOSystem::Exists(file);
  }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    return regular(file) ? DefaultIOSystem::Open(file, mode) : nullptr;
  }

 private:
  static bool regular(const char* file) {
    struct stat st;
    return file != nullptr && ::stat(file, &st) == 0 && S_ISREG(st.st_mode);
  }
};

// Whether the process is asleep (state S or D in /proc/<pid>/stat: waiting, not running).
bool sleeping(pid_t pid) {
  char path[64];
  std::snprintf(path, sizeof path, "/proc/%d/stat", static_cast<int>(pid));
  std::FILE* f = std::fopen(path, "r");
  if (f == nullptr) return false;
  char text[512];
  const size_t n = std::fread(text, 1, sizeof text - 1, f);
  std::fclose(f);
  text[n] = '\0';
  const char* close = std::strrchr(text, ')');  // the command name may hold spaces and ')'
  return close != nullptr && close[1] == ' ' && (close[2] == 'S' || close[2] == 'D');
}

Status import_here(const std::string& path, const std::string& display, LoadedMesh* out) {
  Assimp::Importer importer;
  importer.SetIOHandler(new RegularFilesOnly);  // the importer owns it
  const aiScene* scene = nullptr;
  std::string why;
  {
    AddressSpaceCap cap(path);
    // Bake node transforms into the vertices; split polygons into triangles. Welding is ours.
    bool out_of_memory = false;
    try {
      scene = importer.ReadFile(
          path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType);
    } catch (const std::bad_alloc&) {
      scene = nullptr;
      out_of_memory = true;
    }
    why = importer.GetErrorString();
    if (scene == nullptr && (out_of_memory || why.find("bad_alloc") != std::string::npos)) {
      char gib[32];
      std::snprintf(gib, sizeof gib, "%.1f", cap.allowance_gib());
      return Status::error(display + ": cannot read: the file asks for more than " + gib +
                           " GiB of memory (assimp ran out)");
    }
  }
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    for (char& c : why)
      if (c == '\n' || c == '\r') c = ' ';
    // No reason from assimp: no importer took the file, or one made an incomplete scene (as
    // LightWave's does when an object file the scene names cannot be read).
    if (why.empty())
      why = scene == nullptr ? "unknown format"
                             : "assimp made an incomplete scene (does the file name another that "
                               "is missing or not a "
                               "regular file?)";
    return Status::error(display + ": cannot read: " + why);
  }
  Mesh& m = out->mesh;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* am = scene->mMeshes[i];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const int32_t base = static_cast<int32_t>(m.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v)
      m.vertices.emplace_back(am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z);
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not part of a solid
      m.faces.push_back({base + static_cast<int32_t>(face.mIndices[0]),
                         base + static_cast<int32_t>(face.mIndices[1]),
                         base + static_cast<int32_t>(face.mIndices[2])});
    }
  }
  if (m.faces.empty()) return Status::error(display + ": no triangles in the scene");
  const size_t dot = path.find_last_of('.');
  out->format = dot == std::string::npos ? "assimp" : path.substr(dot + 1);
  out->single_precision = true;
  return Status::ok();
}

// ---- the child's report, through the pipe ----
// 'E' then the one-line message; or 'M', the vertex and face counts (uint64), the vertices
// (3 doubles each; float32 values, so exact) and the faces (3 int32 each).
template <typename T>
void put(std::string* s, const T& v) {
  s->append(reinterpret_cast<const char*>(&v), sizeof v);
}

std::string encode(const Status& s, const LoadedMesh& m) {
  if (!s) return "E" + s.message();
  std::string out = "M";
  put(&out, static_cast<uint64_t>(m.mesh.vertices.size()));
  put(&out, static_cast<uint64_t>(m.mesh.faces.size()));
  for (const Vec3& v : m.mesh.vertices)
    for (int i = 0; i < 3; ++i) put(&out, v[i]);
  for (const Face& f : m.mesh.faces)
    for (int i = 0; i < 3; ++i) put(&out, f[i]);
  out += m.format;
  return out;
}

// False when the bytes are not a whole report (the child died while writing).
bool decode(const std::string& in, const std::string& display, Status* s, LoadedMesh* m) {
  if (in.empty()) return false;
  if (in[0] == 'E') {
    *s = Status::error(in.substr(1));
    return true;
  }
  if (in[0] != 'M' || in.size() < 17) return false;
  uint64_t nv, nf;
  std::memcpy(&nv, in.data() + 1, 8);
  std::memcpy(&nf, in.data() + 9, 8);
  if (nv > in.size() / 24 || nf > in.size() / 12 || in.size() < 17 + nv * 24 + nf * 12)
    return false;
  m->mesh.vertices.resize(nv);
  m->mesh.faces.resize(nf);
  const char* p = in.data() + 17;
  for (Vec3& v : m->mesh.vertices)
    for (int i = 0; i < 3; ++i, p += 8) std::memcpy(&v[i], p, 8);
  for (Face& f : m->mesh.faces)
    for (int i = 0; i < 3; ++i, p += 4) std::memcpy(&f[i], p, 4);
  m->format = in.substr(17 + nv * 24 + nf * 12);
  m->single_precision = true;
  *s = Status::ok();
  // Assimp's indices are unsigned and per mesh; one past int32 or past the vertices would
  // index out of bounds later.
  for (const Face& f : m->mesh.faces)
    for (int32_t i : f)
      if (i < 0 || static_cast<uint64_t>(i) >= nv)
        *s = Status::error(display + ": a face refers to a vertex that does not exist");
  return true;
}

bool write_all(int fd, const std::string& s) {
  size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

[[noreturn]] void run_child(int fd, const std::string& path, const std::string& display,
                            double cpu_seconds) {
  // No core files from a crashing importer, and no output from it either.
  struct rlimit no_core {
    0, 0
  };
  ::setrlimit(RLIMIT_CORE, &no_core);
  const rlim_t cpu = static_cast<rlim_t>(std::ceil(cpu_seconds));
  struct rlimit cpu_limit {
    cpu, cpu + 1
  };  // SIGXCPU at the soft limit, SIGKILL a second later
  ::setrlimit(RLIMIT_CPU, &cpu_limit);
  const int null = ::open("/dev/null", O_WRONLY);
  if (null >= 0) {
    ::dup2(null, 1);
    ::dup2(null, 2);
  }
  LoadedMesh m;
  Status s;
  try {
    s = import_here(path, display, &m);
  } catch (const std::exception& e) {
    s = Status::error(display + ": cannot read: assimp failed: " + e.what());
  }
  _exit(write_all(fd, encode(s, m)) ? 0 : 1);
}

}  // namespace

double assimp_cpu_seconds(uint64_t file_bytes) {
  return 20.0 + 2.0 * static_cast<double>(file_bytes) / (1 << 20);
}

Status load_with_assimp(const std::string& path, const std::string& display, LoadedMesh* out,
                        double cpu_seconds) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    return Status::error(display + ": cannot start the importer: " + std::strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    return Status::error(display + ": cannot start the importer: " + std::strerror(err));
  }
  if (pid == 0) {
    ::close(fds[0]);
    run_child(fds[1], path, display, cpu_seconds);
  }
  ::close(fds[1]);
  // The CPU limit ends a loop; a child that sleeps (it should not) is killed after twice that
  // in wall time plus 10 s.
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::milliseconds(static_cast<int64_t>(1000 * (2 * cpu_seconds + 10)));
  std::string got;
  bool timed_out = false, waiting = false;
  char buf[1 << 16];
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      waiting = sleeping(pid);
      ::kill(pid, SIGKILL);
      break;
    }
    struct pollfd p {
      fds[0], POLLIN, 0
    };
    const int r = ::poll(&p, 1, static_cast<int>(std::min<int64_t>(left.count(), 1000)));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) continue;
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got.append(buf, static_cast<size_t>(n));
  }
  ::close(fds[0]);
  int status = 0;
  struct rusage usage {};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  const double cpu_used = usage.ru_utime.tv_sec + 1e-6 * usage.ru_utime.tv_usec +
                          usage.ru_stime.tv_sec + 1e-6 * usage.ru_stime.tv_usec;
  char limit[32];
  std::snprintf(limit, sizeof limit, "%.0f", cpu_seconds);
  // SIGXCPU, or SIGKILL after it, with the CPU time spent: the limit; SIGKILL before it is
  // spent is an outside kill (the kernel's, out of memory) unless it was ours (timed_out).
  const bool killed =
      WIFSIGNALED(status) && (WTERMSIG(status) == SIGXCPU || WTERMSIG(status) == SIGKILL);
  // Our wall-clock kill of an importer that was asleep then (waiting on a file, not looping,
  // which a starved machine could also keep under its CPU limit). A pipe a scene named did this
  // until RegularFilesOnly; no file is known to do it since, so this is the safety net's message.
  if (timed_out && waiting) {
    char waited[32];
    std::snprintf(waited, sizeof waited, "%.0f", 2 * cpu_seconds + 10);
    return Status::error(
        display + ": cannot read: assimp waited " + waited +
        " s without finishing (does the file name another that blocks, such as a pipe?)");
  }
  if (timed_out || (killed && (WTERMSIG(status) == SIGXCPU || cpu_used >= cpu_seconds - 0.5)))
    return Status::error(display + ": cannot read: assimp did not finish within " + limit +
                         " s of CPU time (a damaged file can make it loop)");
  if (killed)
    return Status::error(display + ": cannot read: assimp's importer was killed (out of memory?)");
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::sigabbrev_np(sig);
    return Status::error(
        display + ": cannot read: assimp's importer crashed on this file (signal " +
        std::to_string(sig) + (name ? std::string(", SIG") + name : std::string()) +
        "); the file is damaged or uses what assimp cannot read");
  }
  Status s;
  LoadedMesh m;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !decode(got, display, &s, &m))
    return Status::error(display + ": cannot read: assimp's importer ended without a result");
  if (!s) return s;
  out->mesh = std::move(m.mesh);
  out->format = m.format;
  out->single_precision = true;
  return Status::ok();
}

void enable_assimp() {
  set_foreign_mesh_reader(
      [](const std::string& path, const std::string& display, uint64_t bytes, LoadedMesh* out) {
        return load_with_assimp(path, display, out, assimp_cpu_seconds(bytes));
      });
}

}  // namespace vobb
