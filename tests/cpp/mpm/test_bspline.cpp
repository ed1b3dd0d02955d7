// Quadratic B-spline (paper Eq 2): partition of unity, zero gradient sum, hand values.
#include <gtest/gtest.h>

#include <random>

#include "mpm/BSpline.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

TEST(BSpline, HandValuesOfEq2) {
  EXPECT_NEAR(bsplineWeight(0.0), 0.75, 1e-15);
  EXPECT_NEAR(bsplineWeight(0.25), 0.75 - 0.0625, 1e-15);
  EXPECT_NEAR(bsplineWeight(-0.5), 0.5, 1e-15);
  EXPECT_NEAR(bsplineWeight(1.0), 0.125, 1e-15);
  EXPECT_NEAR(bsplineWeight(-1.2), 0.5 * 0.09, 1e-15);
  EXPECT_NEAR(bsplineWeight(1.5), 0.0, 1e-15);
  EXPECT_NEAR(bsplineWeight(2.0), 0.0, 1e-15);
  EXPECT_NEAR(bsplineDerivative(0.25), -0.5, 1e-15);
  EXPECT_NEAR(bsplineDerivative(-1.0), 0.5, 1e-15);
  EXPECT_NEAR(bsplineDerivative(1.0), -0.5, 1e-15);
}

TEST(BSpline, StencilMatchesEq2AndIsAPartitionOfUnity) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(2.0, 20.0);
  const double invDx = 1.0 / 0.013;
  for (int t = 0; t < 1000; ++t) {
    const double g[3] = {u(rng), u(rng), u(rng)};
    Stencil<double> st;
    st.compute(g);
    double sum = 0, gs[3] = {0, 0, 0}, first[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          const double w = st.weight(i, j, k);
          const int idx[3] = {i, j, k};
          double ref = 1;
          for (int d = 0; d < 3; ++d) ref *= bsplineWeight(g[d] - (st.base[d] + idx[d]));
          ASSERT_NEAR(w, ref, 1e-14);
          const Vec3T<double> gw = st.gradient(i, j, k, invDx);
          for (int d = 0; d < 3; ++d) {
            double dref = invDx;
            for (int e = 0; e < 3; ++e) {
              const double r = g[e] - (st.base[e] + idx[e]);
              dref *= e == d ? bsplineDerivative(r) : bsplineWeight(r);
            }
            ASSERT_NEAR(gw[d], dref, 1e-12 * invDx);
            gs[d] += gw[d];
            first[d] += (st.base[d] + idx[d]) * w;  // sum w_i x_i = x (linear completeness)
          }
          sum += w;
        }
    ASSERT_NEAR(sum, 1.0, 1e-14);
    for (int d = 0; d < 3; ++d) {
      ASSERT_NEAR(gs[d], 0.0, 1e-13 * invDx);
      ASSERT_NEAR(first[d], g[d], 1e-12);
    }
  }
}
