// Tiny fixed-size vector/tensor types shared by the CPU loops and the CUDA kernels.
// No Eigen here: everything must compile as __host__ __device__ code under nvcc.
// T is float or double. Symmetric tensors (Cauchy stress) are stored as 6 values in
// Voigt order xx yy zz yz xz xy, the order used by ParticleSet::stress.
#pragma once
#include <cmath>

#if defined(__CUDACC__)
#define MPM_HD __host__ __device__
#define MPM_HD_INLINE __host__ __device__ __forceinline__
#else
#define MPM_HD
// Inlined on the host too: a CPU loop over particles is vectorized only when every call in it
// is inlined, which the compiler's size limits would otherwise decide case by case.
#define MPM_HD_INLINE inline __attribute__((always_inline))
#endif

// Loops over the components of a value of several lanes (P2G shares, G2P sums): one SIMD
// instruction per register on the CPU; plain loops in device code.
#if defined(_OPENMP) && !defined(__CUDA_ARCH__)
#define MPM_SIMD _Pragma("omp simd")
#else
#define MPM_SIMD
#endif

namespace mpmsdem {

// Scalar functions that resolve to the CUDA device overloads in device code and to std:: in
// host code (float stays float on both sides).
#if defined(__CUDA_ARCH__)
#define MPMSDEM_HD_MATH(f) f
#else
#define MPMSDEM_HD_MATH(f) std::f
#endif
template <typename T>
MPM_HD_INLINE T hdSqrt(T a) { return MPMSDEM_HD_MATH(sqrt)(a); }
template <typename T>
MPM_HD_INLINE T hdAbs(T a) { return MPMSDEM_HD_MATH(fabs)(a); }
template <typename T>
MPM_HD_INLINE T hdFloor(T a) { return MPMSDEM_HD_MATH(floor)(a); }
template <typename T>
MPM_HD_INLINE T hdCbrt(T a) { return MPMSDEM_HD_MATH(cbrt)(a); }
template <typename T>
MPM_HD_INLINE T hdLog1p(T a) { return MPMSDEM_HD_MATH(log1p)(a); }
template <typename T>
MPM_HD_INLINE T hdAtan2(T y, T x) { return MPMSDEM_HD_MATH(atan2)(y, x); }
template <typename T>
MPM_HD_INLINE bool hdIsFinite(T a) { return MPMSDEM_HD_MATH(isfinite)(a); }
#undef MPMSDEM_HD_MATH

template <typename T>
struct Vec3T {
  T x, y, z;
  MPM_HD_INLINE T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  MPM_HD_INLINE T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

template <typename T>
MPM_HD_INLINE Vec3T<T> operator+(const Vec3T<T>& a, const Vec3T<T>& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename T>
MPM_HD_INLINE Vec3T<T> operator-(const Vec3T<T>& a, const Vec3T<T>& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename T>
MPM_HD_INLINE Vec3T<T> operator*(T s, const Vec3T<T>& a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename T>
MPM_HD_INLINE T dot(const Vec3T<T>& a, const Vec3T<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Full 3x3 matrix, row-major: m[i][j].
template <typename T>
struct Mat3T {
  T m[3][3];
  MPM_HD_INLINE static Mat3T zero() {
    Mat3T r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = T(0);
    return r;
  }
  MPM_HD_INLINE T trace() const { return m[0][0] + m[1][1] + m[2][2]; }
  MPM_HD_INLINE T det() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
};

// Symmetric tensor, Voigt order xx yy zz yz xz xy.
template <typename T>
struct Sym6T {
  T s[6];
  MPM_HD_INLINE static Sym6T zero() { return {{T(0), T(0), T(0), T(0), T(0), T(0)}}; }
  // Component (i, j) of the full tensor.
  MPM_HD_INLINE T at(int i, int j) const {
    if (i == j) return s[i];
    const int k = 6 - i - j;  // (1,2)->3 yz, (0,2)->4 xz, (0,1)->5 xy
    return s[k];
  }
  MPM_HD_INLINE T trace() const { return s[0] + s[1] + s[2]; }
};

// Double contraction a:b of two symmetric tensors (off-diagonal terms count twice).
template <typename T>
MPM_HD_INLINE T ddot(const Sym6T<T>& a, const Sym6T<T>& b) {
  return a.s[0] * b.s[0] + a.s[1] * b.s[1] + a.s[2] * b.s[2] + T(2) * (a.s[3] * b.s[3] + a.s[4] * b.s[4] + a.s[5] * b.s[5]);
}

// Symmetric part of a full matrix.
template <typename T>
MPM_HD_INLINE Sym6T<T> symPart(const Mat3T<T>& L) {
  const T h = T(0.5);
  return {{L.m[0][0], L.m[1][1], L.m[2][2], h * (L.m[1][2] + L.m[2][1]), h * (L.m[0][2] + L.m[2][0]),
           h * (L.m[0][1] + L.m[1][0])}};
}

// W*S - S*W for a skew W (given as full matrix) and symmetric S; the result is symmetric.
template <typename T>
MPM_HD_INLINE Sym6T<T> jaumannTerm(const Mat3T<T>& W, const Sym6T<T>& S) {
  T ws[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) ws[i][j] = W.m[i][0] * S.at(0, j) + W.m[i][1] * S.at(1, j) + W.m[i][2] * S.at(2, j);
  // (S W)_{ij} = sum_k S_ik W_kj = -(W S)_{ji} because W^T = -W and S^T = S.
  // Hence W S - S W = ws + ws^T.
  return {{T(2) * ws[0][0], T(2) * ws[1][1], T(2) * ws[2][2], ws[1][2] + ws[2][1], ws[0][2] + ws[2][0],
           ws[0][1] + ws[1][0]}};
}

}  // namespace mpmsdem
