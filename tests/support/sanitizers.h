#pragma once
// ZEROSET_TEST_UNDER_ASAN is 1 in a build with AddressSanitizer (GCC's and clang's ways of
// saying so), else 0: tests that cannot run under it, or must run smaller, look at it.
#if defined(__SANITIZE_ADDRESS__)
#define ZEROSET_TEST_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ZEROSET_TEST_UNDER_ASAN 1
#endif
#endif
#ifndef ZEROSET_TEST_UNDER_ASAN
#define ZEROSET_TEST_UNDER_ASAN 0
#endif
