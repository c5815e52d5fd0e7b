#pragma once

// Whether allocation_counter.cpp also replaces the C allocator: not under a sanitizer whose
// runtime owns malloc (GCC says so with __SANITIZE_*, clang with __has_feature).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HAPTIC_COUNTS_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer) || __has_feature(hwaddress_sanitizer)
#define HAPTIC_COUNTS_MALLOC 0
#else
#define HAPTIC_COUNTS_MALLOC 1
#endif
#else
#define HAPTIC_COUNTS_MALLOC 1
#endif
