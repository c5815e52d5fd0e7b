#pragma once

// The queues between hapticd's RT thread and one non-RT thread: Boost.Lockfree's single-
// producer single-consumer ring, with its capacity fixed at compile time (no allocation, wait-
// free push and pop). Not iceoryx_hoofs' queues: in iceoryx 2.0 neither orders the reuse of a
// slot after it was read (LockFreeQueue's reader never releases a slot it read, FiFo's pop
// stores its index relaxed), a data race in the C++ memory model that ThreadSanitizer reports
// on every wrap. Boost's ring releases the read index after the copy and acquires it before
// writing, so the exchange is race-free and TSan checks it as it is.

#include <boost/lockfree/spsc_queue.hpp>
#include <cstddef>

namespace haptic::daemon {

template <typename T, std::size_t Capacity>
using SpscQueue = boost::lockfree::spsc_queue<T, boost::lockfree::capacity<Capacity>>;

}  // namespace haptic::daemon
