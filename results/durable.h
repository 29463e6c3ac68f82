// Making a finished file survive a crash: its bytes (and then its directory entry) reach the disk
// before anyone is told it exists. Used by every atomic "write temporary, fsync, rename" here.
#pragma once
#include <string>

namespace sirl {

// fsync of a file or a directory; silently does nothing if it cannot be opened.
void fsync_path(const std::string& path);

}  // namespace sirl
