#pragma once
// Which sanitizer instruments the file being compiled, under GCC or Clang.
//
// APERTURE_ASAN: defined (as 1) under AddressSanitizer.
#if defined(__SANITIZE_ADDRESS__)
#define APERTURE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define APERTURE_ASAN 1
#endif
#endif
