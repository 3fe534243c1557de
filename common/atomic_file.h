// Atomic file output: the content goes to a temporary file beside the target, is flushed to
// disk, and is renamed over the target. A reader sees the old file or the whole new one, never
// half of it; a crash leaves at most a stray "<target>.tmp.<pid>" file.
#pragma once

#include <string>

#include "common/status.h"

namespace vobb {

Status write_file_atomic(const std::string& path, const std::string& content);

}  // namespace vobb
