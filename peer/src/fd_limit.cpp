#include "fd_limit.h"

#include <sys/resource.h>

#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>

#include "csculpt/error.h"

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

void require_free_descriptors(std::size_t needed) {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return;
  std::error_code error;
  std::size_t open = 0;
  for (std::filesystem::directory_iterator it("/proc/self/fd", error), end; !error && it != end;
       it.increment(error))
    ++open;
  if (error || open == 0) return;  // no /proc: nothing to count
  if (open + needed <= limit.rlim_cur) return;
  throw IoError("too few file descriptors for a session: the open-file limit is " +
                std::to_string(limit.rlim_cur) + " and " + std::to_string(open) +
                " are open; a session needs " + std::to_string(needed) +
                " free (raise the limit, e.g. `ulimit -n 1024`)");
}

}  // namespace csculpt::peer
