#pragma once
// Four-lane float and int vectors for the integrator's inner loops (internal
// to src/core/occupancy).
#include <cmath>
#include <cstdint>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON) && defined(__aarch64__)
#include <arm_neon.h>
#endif

namespace semexp {
namespace occupancy {
namespace lanes {

// Four-lane vectors (GCC/Clang vector extensions: SSE2 or NEON registers).
// Element-wise IEEE operations, so each lane computes what the scalar code
// would; selections are written as bit masks, which every target has.
constexpr int kLanes = 4;
typedef float Vf __attribute__((vector_size(16)));
typedef std::int32_t Vi __attribute__((vector_size(16)));

inline Vi bits(Vf a) {
  Vi r;
  std::memcpy(&r, &a, sizeof(r));
  return r;
}
inline Vf floats(Vi a) {
  Vf r;
  std::memcpy(&r, &a, sizeof(r));
  return r;
}
/// m ? a : b per lane (m: all ones or zero).
inline Vf select(Vi m, Vf a, Vf b) { return floats((m & bits(a)) | (~m & bits(b))); }

/// Square root per lane (correctly rounded, like std::sqrt).
inline Vf sqrtLanes(Vf a) {
#if defined(__SSE2__)
  __m128 r;
  std::memcpy(&r, &a, sizeof(r));
  r = _mm_sqrt_ps(r);
  std::memcpy(&a, &r, sizeof(r));
  return a;
#elif defined(__ARM_NEON) && defined(__aarch64__)
  float32x4_t r;
  std::memcpy(&r, &a, sizeof(r));
  r = vsqrtq_f32(r);
  std::memcpy(&a, &r, sizeof(r));
  return a;
#else
  for (int k = 0; k < kLanes; ++k) a[k] = std::sqrt(a[k]);
  return a;
#endif
}

}  // namespace lanes
}  // namespace occupancy
}  // namespace semexp
