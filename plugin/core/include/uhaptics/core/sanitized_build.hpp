#pragma once
// Whether this translation unit is built with AddressSanitizer or ThreadSanitizer. GCC announces
// them with __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__; the clang this project's ASan tree uses
// (Debian 12's clang 14) only through __has_feature, so both are asked.

namespace uhaptics {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitizedBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif
#else
inline constexpr bool kSanitizedBuild = false;
#endif

}  // namespace uhaptics
