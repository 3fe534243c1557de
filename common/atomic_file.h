// Atomic file output: the content goes to a temporary file beside the target, is flushed to
// disk, and is renamed over the target. A reader sees the old file or the whole new one, never
// half of it; a crash leaves at most a stray ".vobb-<pid>-<n>.tmp" file in the target's folder.
// A symbolic link is followed (its target is replaced, the link kept). A target that exists
// and is not a regular file (a device such as /dev/null, a pipe) is written to in place, since
// it must not be replaced; a folder is refused.
#pragma once

#include <string>

#include "common/status.h"

namespace vobb {

Status write_file_atomic(const std::string& path, const std::string& content);

}  // namespace vobb
