#pragma once
// Whether this test program is built with AddressSanitizer or ThreadSanitizer (as
// test/scripts/test_sanitizers_asan.sh and _tsan.sh build it), as the compiler says. The slowest
// tests repeat one code path over many seeds, samples or frames; under a sanitizer, where each
// repetition costs 5 to 60 times as much, they check fewer of them (sanitizedCount): the
// sanitizer looks for memory and undefined-behaviour faults on each path, which the first
// repetitions already take, and the same test's full count runs in the normal build of every
// test run.

namespace hameritt {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)  // g++
constexpr bool kSanitized = true;
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

// `full` normally, `sanitized` in a sanitizer build.
constexpr int sanitizedCount(int full, int sanitized) { return kSanitized ? sanitized : full; }

}  // namespace hameritt
