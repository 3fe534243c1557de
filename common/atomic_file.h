// Atomic file output: the content goes to a temporary file beside the target, is flushed to
// disk, and is renamed over the target. A reader sees the old file or the whole new one, never
// half of it; a crash leaves at most a stray ".vobb-<pid>-<n>.tmp" file in the target's folder.
// A symbolic link is followed (its target is replaced, the link kept). A target that exists
// and is not a regular file (a device such as /dev/null, a pipe) is written to in place, since
// it must not be replaced; a folder is refused, and so is a named pipe that no process opens
// for reading within kPipeReaderWaitSeconds (its open would otherwise block forever).
#pragma once

#include <string>

#include "common/status.h"

namespace vobb {

inline constexpr int kPipeReaderWaitSeconds = 5;
Status write_file_atomic(const std::string& path, const std::string& content);

// The file a write to `path` replaces: `path` itself, or, where `path` is a symbolic link, the
// end of its chain of links (each relative link read against its own folder), whether that
// file exists yet or not, so that the link is kept and its target written. A loop, or a
// chain of more than 40 links, is an error naming `path`.
Status output_target(const std::string& path, std::string* target);

// Removes from `folder` (not below it) the stray temporary files of runs that were killed
// mid-write: regular files named ".vobb-<pid>-<n>.tmp" that no writer holds (write_file_atomic
// locks its temporary file with flock from its creation to its close) and that were last
// written over kStrayAgeSeconds ago (which covers the moment between a writer's creating the
// file and locking it, and between its closing and renaming it). Neither test uses the pid, so
// a run in another pid namespace sharing the folder is not disturbed, and a killed run's file
// goes even where this run was given the same pid. Returns how many were removed; a folder
// that cannot be read removes nothing. For folders vobb owns, such as checkpoints; it is not
// run on users' output folders.
constexpr int kStrayAgeSeconds = 60;
size_t remove_stray_temporaries(const std::string& folder);

// Why `dir`, which is not a folder, cannot hold an output: "X is not a folder" where something
// else is there, "no such folder X" where nothing is.
std::string not_a_folder(const std::string& dir);

// Whether the folder `dir` takes a new file: a probe file is made there and removed. `what`
// begins the error line (the option and its value).
Status check_folder_takes_files(const std::string& what, const std::string& dir);

// Makes a checkpoint folder if it is not there (its parent must exist), checks that it takes files
// (refused now, not warned about at every save of a run that could never resume), and clears
// it of the temporary files of runs killed mid-write. `what` begins the error line.
Status make_checkpoint_folder(const std::string& what, const std::string& folder);

}  // namespace vobb
