// Whether this test binary is built with AddressSanitizer (the CI's sanitizer build): the code
// under test runs several times slower there and ASan keeps freed memory in its quarantine, so
// tests of timing or memory growth relax those checks (and say so) in that build only.
#pragma once

namespace selfsense::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

}  // namespace selfsense::test
