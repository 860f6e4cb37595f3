#pragma once
/// @file atomic_file.hpp
/// Saving a file so that a failed save never leaves a truncated or
/// half-written file where a good one was: everything goes to a temporary
/// file beside the target, which replaces the target (rename) only once it
/// was written, flushed, synced and closed without an error.

#include <functional>
#include <ostream>
#include <string>

namespace semexp {

/// Writes `path` through `write` atomically (see the file comment). A `path`
/// that is a symlink is followed: the file it names is replaced, the link
/// kept. A target that exists and is not a regular file (a directory, a
/// device such as /dev/full) is refused.
/// @throws std::runtime_error naming the path and what failed; the previous
///         file is then unchanged and no temporary file is left. Exceptions
///         thrown by `write` are passed on the same way.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace semexp
