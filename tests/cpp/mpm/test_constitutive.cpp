// Appendix B mu(I) model (with the corrections of docs/physics.md), the Appendix A wall condition,
// the G2P grid sums (one particle and groups of one stencil base), and the G2P update of one
// particle (Eq 4 and the stress update) from its gathered values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "mpm/Constitutive.hpp"
#include "mpm/GridBoundary.hpp"
#include "mpm/MpmKernelsCommon.hpp"

using namespace mpmsdem;
using namespace mpmsdem::mpm;

namespace {
ConstitutiveConst<double> material() {
  GranularMaterial m;  // Table 1 glass beads: E 1 MPa, nu 0.3, mu_s 0.24, mu_2 0.65
  return makeConstitutiveConst<double>(m);
}
Sym6T<double> isotropic(double p) { return {{-p, -p, -p, 0, 0, 0}}; }
}  // namespace

TEST(Constitutive, ElasticStepIsHooke) {
  const auto c = material();
  EXPECT_NEAR(c.G, 1e6 / 2.6, 1e-6);
  EXPECT_NEAR(c.lambda, 1e6 * 0.3 / (1.3 * 0.4), 1e-6);
  Sym6T<double> s = isotropic(1000);
  Mat3T<double> L = Mat3T<double>::zero();
  // symmetric (W = 0) small strain rate with volumetric and deviatoric parts [1/s]
  L.m[0][0] = -2e-3; L.m[1][1] = 1e-3; L.m[2][2] = -4e-3;
  L.m[0][1] = L.m[1][0] = 5e-4; L.m[1][2] = L.m[2][1] = -3e-4; L.m[0][2] = L.m[2][0] = 2e-4;
  const double dt = 1e-3, rho = 1700;
  double gdp = -1;
  const auto phase = updateStress(s, L, dt, rho, c, gdp);
  EXPECT_EQ(phase, kPhaseElastic);
  EXPECT_EQ(gdp, 0.0);
  const double tr = -5e-3;
  const double D[6] = {-2e-3, 1e-3, -4e-3, -3e-4, 2e-4, 5e-4};
  for (int k = 0; k < 6; ++k) {
    const double expect = (k < 3 ? -1000.0 + dt * c.lambda * tr : 0.0) + dt * 2 * c.G * D[k];
    EXPECT_NEAR(s.s[k], expect, 1e-12 * 1000);
  }
}

TEST(Constitutive, PlasticStepReturnsOntoMuISurface) {
  const auto c = material();
  const double p0 = 1000, dt = 1e-4, rate = 5.0;
  Sym6T<double> s = isotropic(p0);
  Mat3T<double> L = Mat3T<double>::zero();
  L.m[0][2] = L.m[2][0] = rate;  // pure shear, W = 0
  double gdp = 0;
  const auto phase = updateStress(s, L, dt, 1700.0, c, gdp);
  ASSERT_EQ(phase, kPhasePlastic);
  const double tauTr = dt * 2 * c.G * rate;  // sqrt(1/2 * 2 * (dt 2G rate)^2)
  ASSERT_GT(tauTr, c.muS * p0);
  double p, tau;
  stressInvariants(s, p, tau);
  EXPECT_NEAR(p, p0, 1e-12 * p0);                    // pressure kept (B.11)
  EXPECT_NEAR(s.s[4] / tau, 1.0, 1e-12);             // deviator direction kept (only xz)
  EXPECT_NEAR(gdp, (tauTr - tau) / (c.G * dt), 1e-9 * gdp);  // B.10
  // On the mu(I) surface: tau = mu(I) p with I = gdp d / sqrt(p / rho_s) (B.2).
  GranularMaterial m;
  const double I = gdp * m.grainDiameter / std::sqrt(p / m.solidDensity);
  const double mu = m.muS + (m.mu2 - m.muS) / (m.I0 / I + 1);
  EXPECT_NEAR(tau, mu * p, 1e-10 * p);
  EXPECT_GT(tau, c.muS * p);
  EXPECT_LT(tau, tauTr);
  // Quadratic B.8 with the corrected alpha_1 = xi G dt sqrt(p_tr).
  const double a1 = c.xi * c.G * dt * std::sqrt(p0);
  const double B = c.mu2 * p0 + tauTr + a1, H = c.mu2 * p0 * tauTr + c.muS * p0 * a1;
  EXPECT_NEAR((tau * tau - B * tau + H) / (B * B), 0.0, 1e-10);
}

TEST(Constitutive, GasifiedBelowCriticalDensityOrInTension) {
  const auto c = material();  // rho_c = rho_0 = 1600
  Mat3T<double> L = Mat3T<double>::zero();
  L.m[0][0] = 1e-3;
  double gdp = 1;
  Sym6T<double> s = isotropic(1000);
  EXPECT_EQ(updateStress(s, L, 1e-4, 1599.0, c, gdp), kPhaseGasified);
  for (double v : s.s) EXPECT_EQ(v, 0.0);
  EXPECT_EQ(gdp, 0.0);
  s = isotropic(-50);  // tension
  EXPECT_EQ(updateStress(s, L, 1e-4, 1700.0, c, gdp), kPhaseGasified);
  for (double v : s.s) EXPECT_EQ(v, 0.0);
}

// Under pure spin (D = 0) the Jaumann update sigma + dt (W sigma - sigma W) keeps the trace
// exactly (tr(W s - s W) = 0), and since s0 : (W s0 - s0 W) = 0 it changes tau only at
// second order: tau'^2 = tau^2 + dt^2 |W s0 - s0 W|^2 / 2, i.e. tau'/tau - 1 <= 2 dt^2 |W|_F^2.
TEST(Constitutive, JaumannSpinKeepsInvariants) {
  const auto c = material();
  Sym6T<double> s{{-1200, -1000, -900, 30, -40, 60}};
  double p0, tau0;
  stressInvariants(s, p0, tau0);
  ASSERT_LT(tau0, c.muS * p0);  // stays elastic
  Mat3T<double> L = Mat3T<double>::zero();
  L.m[0][1] = 3; L.m[1][0] = -3; L.m[0][2] = -2; L.m[2][0] = 2; L.m[1][2] = 1.5; L.m[2][1] = -1.5;
  const double dt = 1e-4;
  Mat3T<double> W = L;
  const Sym6T<double> C = jaumannTerm(W, s);
  const double expectTau = std::sqrt(tau0 * tau0 + dt * dt * ddot(C, C) / 2);
  double gdp;
  ASSERT_EQ(updateStress(s, L, dt, 1700.0, c, gdp), kPhaseElastic);
  double p1, tau1;
  stressInvariants(s, p1, tau1);
  EXPECT_NEAR(p1, p0, 1e-12 * p0);
  EXPECT_NEAR(tau1, expectTau, 1e-12 * tau0);
  const double w2 = 2 * (9 + 4 + 2.25);
  EXPECT_LE(tau1 / tau0 - 1, 2 * dt * dt * w2);
  EXPECT_GE(tau1 / tau0 - 1, 0.0);
}

TEST(GridBoundary, CoulombWallRemovesInwardNormalAndCapsTangential) {
  // low z wall (outward normal -z), mu 0.5: v_n = 2 removed, |v_t| = 5 reduced by 1
  Vec3T<double> v{3, 4, -2};
  applyWall(v, 2, -1.0, 0.5);
  EXPECT_NEAR(v.z, 0, 1e-15);
  EXPECT_NEAR(v.x, 3 * 0.8, 1e-14);
  EXPECT_NEAR(v.y, 4 * 0.8, 1e-14);
  // sticking: |v_t| = 0.5 <= 0.5 * 2
  v = {0.3, 0.4, -2};
  applyWall(v, 2, -1.0, 0.5);
  EXPECT_EQ(v.x, 0);
  EXPECT_EQ(v.y, 0);
  // separating: untouched
  v = {3, 4, 2};
  applyWall(v, 2, -1.0, 0.5);
  EXPECT_EQ(v.x, 3);
  EXPECT_EQ(v.z, 2);
  // no-slip high x wall: tangential zero, outward (inward-moving) normal removed
  v = {1, 4, 2};
  applyWall(v, 0, 1.0, -1.0);
  EXPECT_EQ(v.x, 0);
  EXPECT_EQ(v.y, 0);
  EXPECT_EQ(v.z, 0);
}

// ------------------------------------------------------------------ the G2P update of one particle
namespace {
// A particle's G2P values at a[c * stride + lane] (kG2P... offsets) and one output slot.
struct G2PCase {
  static constexpr int kStride = 4, kLane = 2;
  double a[kG2PValues * kStride] = {};
  double x[3][kStride], v[3][kStride], s[6][kStride], J[kStride], gdp[kStride];
  std::uint8_t phase[kStride];
  ParticleOut<double> out;
  GridConst<double> g;
  StepConst<double> sc;
  G2PCase() {
    MpmParams prm;  // 10 cells of 1 cm: admissible box [0.02, 0.08] m on each axis
    g = makeGridConst<double>(prm, 1e-12);
    sc.dt = 1e-3;
    sc.alpha = 0.99;
    sc.maxSpeed = 100;
    sc.mat = material();
    for (int d = 0; d < 3; ++d) out.x[d] = x[d], out.v[d] = v[d];
    for (int k = 0; k < 6; ++k) out.s[k] = s[k];
    out.J = J, out.gdp = gdp, out.phase = phase;
    const double dv[3] = {0.01, -0.02, -0.00981}, vPic[3] = {0.5, 0.1, -0.3}, x0[3] = {0.05, 0.04, 0.03},
                 v0[3] = {0.49, 0.12, -0.29};
    for (int d = 0; d < 3; ++d) {
      set(kG2PDv + d, dv[d]);
      set(kG2PVPic + d, vPic[d]);
      set(kG2PX + d, x0[d]);
      set(kG2PV + d, v0[d]);
    }
    const double L[3][3] = {{-2e-2, 5e-3, 0}, {1e-2, 4e-3, -3e-3}, {0, 2e-3, -1e-2}};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) set(kG2PL + 3 * r + c, L[r][c]);
    for (int k = 0; k < 6; ++k) set(kG2PSigma + k, stress0().s[k]);
    set(kG2PJ, 0.95);
    set(kG2PMass, 1.7e-4);
    set(kG2PVol0, 1e-7);
  }
  // 1 kPa pressure and a shear stress above mu_s p: the update goes through the return map.
  static Sym6T<double> stress0() {
    Sym6T<double> s = isotropic(1000);
    s.s[4] = 300;
    return s;
  }
  void set(int c, double value) { a[c * kStride + kLane] = value; }
  double get(int c) const { return a[c * kStride + kLane]; }
  Mat3T<double> L() const {
    Mat3T<double> m;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m.m[r][c] = get(kG2PL + 3 * r + c);
    return m;
  }
  bool update(double& speed, int& ph) { return g2pUpdate(a + kLane, kStride, kLane, out, g, sc, speed, ph); }
};
}  // namespace

TEST(G2PUpdate, GivesEq4TheVolumeRatioAndTheStressUpdateOfTheLaneItReads) {
  G2PCase t;
  double speed = -1;
  int ph = -1;
  ASSERT_TRUE(t.update(speed, ph));
  Vec3T<double> v{0, 0, 0};
  for (int d = 0; d < 3; ++d) {
    v[d] = 0.99 * (t.get(kG2PV + d) + t.get(kG2PDv + d)) + 0.01 * t.get(kG2PVPic + d);
    EXPECT_NEAR(t.v[d][G2PCase::kLane], v[d], 1e-15);
    EXPECT_NEAR(t.x[d][G2PCase::kLane], t.get(kG2PX + d) + 1e-3 * t.get(kG2PVPic + d), 1e-16);
  }
  EXPECT_NEAR(speed, std::sqrt(dot(v, v)), 1e-15);
  Mat3T<double> F = t.L();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) F.m[r][c] = (r == c ? 1.0 : 0.0) + 1e-3 * F.m[r][c];
  const double J = 0.95 * F.det();
  EXPECT_NEAR(t.J[G2PCase::kLane], J, 1e-15);
  Sym6T<double> s = G2PCase::stress0();
  double gdp = -1;
  const std::uint8_t phase = updateStress(s, t.L(), 1e-3, 1.7e-4 / (J * 1e-7), material(), gdp);
  EXPECT_EQ(ph, phase);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(t.s[k][G2PCase::kLane], s.s[k], 1e-9) << k;
  EXPECT_NEAR(t.gdp[G2PCase::kLane], gdp, 1e-12);
  EXPECT_EQ(ph, kPhasePlastic);
  EXPECT_GT(gdp, 0);
}

TEST(G2PUpdate, AnInvertedPointFailsKeepingItsStress) {
  G2PCase t;
  t.set(kG2PL, -2e3);  // 1 + dt L_xx = -1: the point is turned inside out (J < 0)
  double speed;
  int ph = -1;
  EXPECT_FALSE(t.update(speed, ph));
  EXPECT_LT(t.J[G2PCase::kLane], 0);
  EXPECT_EQ(ph, kPhaseGasified);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(t.s[k][G2PCase::kLane], t.get(kG2PSigma + k)) << k;
  EXPECT_EQ(t.gdp[G2PCase::kLane], 0.0);
}

TEST(G2PUpdate, ANonFiniteOrTooFastPointFails) {
  double speed;
  int ph;
  G2PCase nan;
  nan.set(kG2PDv + 1, std::nan(""));
  EXPECT_FALSE(nan.update(speed, ph));
  G2PCase fast;
  fast.set(kG2PV, 200);  // above StepConst::maxSpeed = 100 m/s
  EXPECT_FALSE(fast.update(speed, ph));
  EXPECT_GT(speed, 100);
  G2PCase crushed;
  crushed.set(kG2PJ, 5e-4);  // below kMinJ
  EXPECT_FALSE(crushed.update(speed, ph));
}

namespace {
// Grid sums of g2pGather written out node by node with Stencil::weight and gradient: the
// reference the grouped, factored sums must match.
template <typename T>
void gatherByNode(const T* x, const T* grid, const GridConst<T>& g, double out[15]) {
  T gc[3];
  for (int d = 0; d < 3; ++d) gc[d] = (x[d] - g.origin[d]) * g.invDx;
  Stencil<T> st;
  st.compute(gc);
  for (int c = 0; c < 15; ++c) out[c] = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        const T* r = grid + kNodeValues * (((st.base[0] + i) * g.nodes[1] + st.base[1] + j) * g.nodes[2] + st.base[2] + k);
        const double w = st.weight(i, j, k);
        const Vec3T<T> dw = st.gradient(i, j, k, g.invDx);
        for (int d = 0; d < 3; ++d) {
          const double vn = r[kNodeVNew + d];
          out[kG2PDv + d] += w * (vn - r[d]);
          out[kG2PVPic + d] += w * vn;
          for (int e = 0; e < 3; ++e) out[kG2PL + 3 * d + e] += vn * dw[e];
        }
      }
}

// Seven particles in one stencil base (grid cell (4, 5, 6) shifted by half a cell) over a grid
// of pseudo-random node velocities. The CPU step gathers a particle in a group of 8 whatever the
// others in it (their number, its lane): it must get the same bits in every group; and the sums
// must be those of the node-by-node formula, as must those of the single-particle g2pGather
// (the CUDA path; the compiler may contract its multiply-adds differently).
template <typename T>
void groupedGatherMatchesOneByOne() {
  MpmParams prm;  // 10 cells of 1 cm
  const GridConst<T> g = makeGridConst<T>(prm, 1e-12);
  std::vector<T> grid(kNodeValues * g.nodes[0] * g.nodes[1] * g.nodes[2]);
  unsigned state = 12345;
  for (T& v : grid) {
    state = state * 1664525u + 1013904223u;
    v = T(state >> 8) / T(1 << 24) - T(0.5);  // [-0.5, 0.5) m/s
  }
  constexpr int n = 7;
  std::vector<T> x[3], vel[3], s[6], J(n, T(1)), mass(n, T(1e-4)), vol0(n, T(1e-7));
  for (auto& c : x) c.resize(n);
  for (auto& c : vel) c.assign(n, T(0.1));
  for (auto& c : s) c.assign(n, T(-100));
  for (int q = 0; q < n; ++q)
    for (int d = 0; d < 3; ++d) x[d][q] = g.origin[d] + g.dx * (T(4.55 + d) + T(0.13) * ((q + d) % 7) + T(0.01) * q);
  ParticleIn<T> in{};
  for (int d = 0; d < 3; ++d) in.x[d] = x[d].data(), in.v[d] = vel[d].data();
  for (int k = 0; k < 6; ++k) in.s[k] = s[k].data();
  in.J = J.data(), in.mass = mass.data(), in.vol0 = vol0.data();
  const int ps[n] = {6, 2, 0, 5, 1, 3, 4};
  T one[kG2PValues * n], eight[kG2PValues * n], alone[kG2PValues * n], threes[kG2PValues * n];
  for (int l = 0; l < n; ++l) g2pGather(ps[l], in, grid.data(), g, one + l, n);
  g2pGatherGroup<8>(ps, n, in, grid.data(), g, eight, n);
  for (int l = 0; l < n; ++l) g2pGatherGroup<8>(ps + l, 1, in, grid.data(), g, alone + l, n);
  for (int l = 0; l < n; l += 3) g2pGatherGroup<8>(ps + l, std::min(3, n - l), in, grid.data(), g, threes + l, n);
  const double tol = sizeof(T) == 8 ? 1e-14 : 1e-5;  // of sums of order 1 m/s (L: 1/dx times that)
  for (int l = 0; l < n; ++l) {
    const int p = ps[l];
    Stencil<T> st;
    T gc[3] = {(x[0][p] - g.origin[0]) * g.invDx, (x[1][p] - g.origin[1]) * g.invDx, (x[2][p] - g.origin[2]) * g.invDx};
    st.compute(gc);
    ASSERT_EQ(st.base[0], 4);  // the test's particles do share one base
    ASSERT_EQ(st.base[1], 5);
    ASSERT_EQ(st.base[2], 6);
    double ref[15];
    T xp[3] = {x[0][p], x[1][p], x[2][p]};
    gatherByNode(xp, grid.data(), g, ref);
    for (int c = 0; c < kG2PValues; ++c) {
      EXPECT_EQ(alone[c * n + l], eight[c * n + l]) << "value " << c << " of particle " << p;
      EXPECT_EQ(threes[c * n + l], eight[c * n + l]) << "value " << c << " of particle " << p;
    }
    for (int c = 0; c < 15; ++c) {
      const double scale = c >= kG2PL ? double(g.invDx) : 1.0;
      EXPECT_NEAR(eight[c * n + l], ref[c], tol * scale) << "sum " << c << " of particle " << p;
      EXPECT_NEAR(one[c * n + l], ref[c], tol * scale) << "sum " << c << " of particle " << p;
    }
    for (int c = 15; c < kG2PValues; ++c) EXPECT_EQ(one[c * n + l], eight[c * n + l]) << "state " << c;
    EXPECT_EQ(eight[kG2PX * n + l], x[0][p]);
    EXPECT_EQ(eight[kG2PMass * n + l], mass[p]);
  }
}
}  // namespace

TEST(G2PGather, AParticleGetsTheSameSumsInAnyGroupOfItsStencilBase) {
  groupedGatherMatchesOneByOne<double>();
  groupedGatherMatchesOneByOne<float>();
}
