// How the daemon's threads share a two-core puck (sched(7)): the threads a pose passes
// through ask for short turns, the registration worker steps back.
#pragma once

#include <string>

namespace floorpose {

// The latency class, for the calling thread and every thread it creates afterwards (DDS
// receive threads, the io thread): the kernel is asked for turns of kShortSliceNs (EEVDF's
// custom slice, Linux 6.12 and later), so that a thread woken by a pose preempts a thread
// running a long computation at once instead of waiting out that thread's slice. Older
// kernels accept and ignore it. Takes no privilege.
inline constexpr long kShortSliceNs = 100'000;  // the kernel's shortest, 0.1 ms
bool UseShortSlices(std::string* error);

// The background class, for the calling thread: nice 10 (a tenth of a nice-0 thread's
// share of a busy core) and the kernel's default slice.
inline constexpr int kBackgroundNice = 10;
bool UseBackgroundPriority(std::string* error);

}  // namespace floorpose
