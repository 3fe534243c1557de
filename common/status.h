// vobb::Status — the error channel of every library call that can meet bad input.
//
// Errors come in three tiers (STYLE §5):
//  - programmer mistakes: VOBB_ASSERT, which aborts with a message;
//  - bad geometry or bad input files: a Status whose message is one line naming the file
//    and the defect (e.g. "dino-open.off: not closed: 14 border edges");
//  - the command line turns a failed Status into exit code 2; nothing below it throws.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#define VOBB_ASSERT(cond, msg)                                                                   \
  do {                                                                                           \
    if (!(cond)) {                                                                               \
      std::fprintf(stderr, "%s:%d: assertion failed: %s: %s\n", __FILE__, __LINE__, #cond, msg); \
      std::abort();                                                                              \
    }                                                                                            \
  } while (0)

namespace vobb {

class Status {
 public:
  Status() = default;
  static Status ok() { return Status(); }
  static Status error(std::string message) {
    Status s;
    s.ok_ = false;
    s.message_ = std::move(message);
    return s;
  }
  bool is_ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  // One line, no trailing newline. Empty when ok.
  const std::string& message() const { return message_; }

 private:
  bool ok_ = true;
  std::string message_;
};

}  // namespace vobb
