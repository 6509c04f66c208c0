#include "daemon/scheduling.h"

#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace floorpose {
namespace {

// sched_setattr(2)'s argument; glibc 2.36 has no wrapper.
struct SchedAttr {
  uint32_t size = sizeof(SchedAttr);
  uint32_t policy = SCHED_OTHER;
  uint64_t flags = 0;
  int32_t nice = 0;
  uint32_t priority = 0;
  uint64_t runtime_ns = 0;  // for SCHED_OTHER: the requested slice, 0 = the default
  uint64_t deadline_ns = 0;
  uint64_t period_ns = 0;
};

bool SetAttr(const SchedAttr& attr, std::string* error) {
  if (syscall(SYS_sched_setattr, 0, &attr, 0) == 0) return true;
  *error = std::string("sched_setattr: ") + std::strerror(errno);
  return false;
}

}  // namespace

bool UseShortSlices(std::string* error) {
  SchedAttr attr;
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
  if (errno != 0) {
    *error = std::string("getpriority: ") + std::strerror(errno);
    return false;
  }
  attr.nice = nice;  // keep it: sched_setattr sets both
  attr.runtime_ns = kShortSliceNs;
  return SetAttr(attr, error);
}

bool UseBackgroundPriority(std::string* error) {
  SchedAttr attr;
  attr.nice = kBackgroundNice;
  if (SetAttr(attr, error)) return true;
  // Where sched_setattr is refused, the nice value alone is most of it.
  if (setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kBackgroundNice) == 0) return true;
  *error += std::string("; setpriority: ") + std::strerror(errno);
  return false;
}

}  // namespace floorpose
