#include "fd_limit.h"

#include <sys/resource.h>

#include <mutex>

namespace csculpt::peer {

void raise_fd_limit() {
  static std::once_flag once;
  std::call_once(once, [] {
    rlimit limit{};
    if (::getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur >= limit.rlim_max) return;
    rlimit raised = limit;
    raised.rlim_cur = limit.rlim_max;
    // An unlimited hard limit is above what the kernel accepts (fs.nr_open); the soft limit
    // then stays where it was rather than guessing a number.
    (void)::setrlimit(RLIMIT_NOFILE, &raised);
  });
}

}  // namespace csculpt::peer
