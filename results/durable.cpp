#include "results/durable.h"

#include <fcntl.h>
#include <unistd.h>

namespace sirl {

void fsync_path(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace sirl
