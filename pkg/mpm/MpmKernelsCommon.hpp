// The three stages of one explicit MPM step (paper §2.1, Fig 1) written once as
// __host__ __device__ functions: the CPU loops (MpmCpu.cpp) and the CUDA kernels
// (cuda/MpmCudaKernels.cuh) call exactly these, in double or float.
//
// Grid layout: one flat array of kGridComponents * nNodes values, component c of node n at
// c * nNodes + n, node (i, j, k) at n = (i * nodes[1] + j) * nodes[2] + k.
// After P2G: c = 0 mass, 1..3 momentum of the particle velocities (sum w m v),
// 4..6 that momentum plus dt times the internal and external particle forces.
// After the grid update: 1..3 old velocity, 4..6 new velocity (gravity, grid hooks and walls
// applied).
#pragma once
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "common/Error.hpp"

#include "mpm/BSpline.hpp"
#include "mpm/Constitutive.hpp"
#include "mpm/GridBoundary.hpp"
#include "mpm/MathHD.hpp"
#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

constexpr int kGridComponents = 7;

// Grid geometry and per-run constants.
template <typename T>
struct GridConst {
  T origin[3];      // lower corner [m]
  T dx, invDx;      // spacing [m] and its inverse
  int cells[3];     // cells per axis
  int nodes[3];     // cells + 1
  T gravity[3];     // [m/s^2]
  T wallFriction[6];
  T massEps;        // nodes with mass <= massEps are treated as empty [kg]
  T lo[3], hi[3];   // admissible particle box (kWallLayer cells inside the faces) [m]
};

// Per-step constants.
template <typename T>
struct StepConst {
  T dt;         // [s]
  T alpha;      // FLIP fraction, Eq 4
  T maxSpeed;   // blow-up threshold on |v_p| [m/s]
  ConstitutiveConst<T> mat;
};

// Particle state read by a step (SoA, one array per component).
template <typename T>
struct ParticleIn {
  const T* x[3];
  const T* v[3];
  const T* s[6];
  const T* J;
  const T* mass;
  const T* vol0;
  const T* fext[3];  // all null when no external forces are set for this step
};

// Particle state written by a step.
template <typename T>
struct ParticleOut {
  T* x[3];
  T* v[3];
  T* s[6];
  T* J;
  T* gdp;
  std::uint8_t* phase;
};

template <typename T>
MPM_HD_INLINE void gridCoordinate(const ParticleIn<T>& P, int p, const GridConst<T>& g, T out[3]) {
  for (int d = 0; d < 3; ++d) out[d] = (P.x[d][p] - g.origin[d]) * g.invDx;
}

// P2G of particle p: calls add(node, m, momentum, momentum + dt * force) for its 27 nodes.
// Internal force -V_p sigma grad(w) with V_p = J V0; external force w f_ext (Eq 14).
template <typename T, typename Scatter>
MPM_HD_INLINE void p2gParticle(int p, const ParticleIn<T>& P, const GridConst<T>& g, T dt, Scatter& add) {
  T gc[3];
  gridCoordinate(P, p, g, gc);
  Stencil<T> st;
  st.compute(gc);
  const T m = P.mass[p];
  const T vol = P.J[p] * P.vol0[p];
  const Vec3T<T> v{P.v[0][p], P.v[1][p], P.v[2][p]};
  T s[6];
  for (int k = 0; k < 6; ++k) s[k] = -dt * vol * P.s[k][p];  // -dt V sigma
  Vec3T<T> fe{T(0), T(0), T(0)};
  if (P.fext[0]) fe = Vec3T<T>{dt * P.fext[0][p], dt * P.fext[1][p], dt * P.fext[2][p]};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        const T w = st.weight(i, j, k);
        const Vec3T<T> gw = st.gradient(i, j, k, g.invDx);
        const T wm = w * m;
        const Vec3T<T> mom{wm * v.x, wm * v.y, wm * v.z};
        // (-dt V sigma) . grad w, sigma symmetric in Voigt order xx yy zz yz xz xy
        const Vec3T<T> imp{s[0] * gw.x + s[5] * gw.y + s[4] * gw.z + w * fe.x,
                           s[5] * gw.x + s[1] * gw.y + s[3] * gw.z + w * fe.y,
                           s[4] * gw.x + s[3] * gw.y + s[2] * gw.z + w * fe.z};
        const int node = ((st.base[0] + i) * g.nodes[1] + (st.base[1] + j)) * g.nodes[2] + (st.base[2] + k);
        add(node, wm, mom, mom + imp);
      }
}

// Grid velocities of one node (Eq 3): v_old = p/m, v_new = (p + dt f)/m + dt g; an empty node
// is zeroed (mass included, so grid hooks see it at rest).
template <typename T>
MPM_HD_INLINE void gridNodeVelocity(int node, T* grid, int nNodes, const GridConst<T>& g, T dt) {
  const T m = grid[node];
  if (!(m > g.massEps)) {
    for (int c = 0; c < kGridComponents; ++c) grid[c * nNodes + node] = T(0);
    return;
  }
  const T inv = T(1) / m;
  for (int d = 0; d < 3; ++d) {
    grid[(1 + d) * nNodes + node] *= inv;
    grid[(4 + d) * nNodes + node] = grid[(4 + d) * nNodes + node] * inv + dt * g.gravity[d];
  }
}

// The walls on the new velocity of one node.
template <typename T>
MPM_HD_INLINE void gridNodeWalls(int node, T* grid, int nNodes, const GridConst<T>& g) {
  int idx[3];
  idx[2] = node % g.nodes[2];
  const int r = node / g.nodes[2];
  idx[1] = r % g.nodes[1];
  idx[0] = r / g.nodes[1];
  Vec3T<T> vn{grid[4 * nNodes + node], grid[5 * nNodes + node], grid[6 * nNodes + node]};
  applyWalls(vn, idx, g.cells, g.wallFriction);
  for (int d = 0; d < 3; ++d) grid[(4 + d) * nNodes + node] = vn[d];
}

// Grid update of one node without grid hooks: velocities, then walls. A solver with hooks
// runs the two halves as separate passes with the hooks between them; the values are the
// same (each half stores and reloads T).
template <typename T>
MPM_HD_INLINE void gridNodeUpdate(int node, T* grid, int nNodes, const GridConst<T>& g, T dt) {
  gridNodeVelocity(node, grid, nNodes, g, dt);
  gridNodeWalls(node, grid, nNodes, g);
}

// Admissible volume ratio J = V/V0 of a material point. A granular material changes its
// volume by tens of per cent at most (random loose to dense packing, or the elastic strain
// p/K under any pressure the flows of interest reach); J below kMinJ (crushed to 1/1000 of its
// volume, denser than the solid grains) or above kMaxJ (torn to 1000 x its volume) only comes
// from a numerical failure, e.g. a step too large for the loading, that would otherwise run
// on with flattened particles. The bounds are 1000 x beyond anything physical so that no
// sound run stops.
constexpr double kMinJ = 1e-3;
constexpr double kMaxJ = 1e3;

// Result of the G2P of one particle.
template <typename T>
struct G2PResult {
  bool ok;    // false: non-finite state, |v| above StepConst::maxSpeed, or J outside [kMinJ, kMaxJ]
  T speed;    // |v_p| after the step [m/s]
};

// G2P and stress update of particle p (Eq 4 and Appendix B): reads P (start of step) and the
// updated grid, writes the new state to Q. Velocity v = alpha (v + sum w dv) + (1 - alpha)
// sum w v_new; position x += dt sum w v_new (clamped to the admissible box);
// L = sum v_new (x) grad w; J *= det(I + dt L); rho = m / (J V0).
template <typename T>
MPM_HD_INLINE G2PResult<T> g2pParticle(int p, const ParticleIn<T>& P, const ParticleOut<T>& Q, const T* grid,
                                       int nNodes, const GridConst<T>& g, const StepConst<T>& sc) {
  T gc[3];
  gridCoordinate(P, p, g, gc);
  Stencil<T> st;
  st.compute(gc);
  Vec3T<T> vPic{T(0), T(0), T(0)}, dv{T(0), T(0), T(0)};
  Mat3T<T> L = Mat3T<T>::zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        const int node = ((st.base[0] + i) * g.nodes[1] + (st.base[1] + j)) * g.nodes[2] + (st.base[2] + k);
        const T w = st.weight(i, j, k);
        const Vec3T<T> gw = st.gradient(i, j, k, g.invDx);
        const Vec3T<T> vo{grid[nNodes + node], grid[2 * nNodes + node], grid[3 * nNodes + node]};
        const Vec3T<T> vn{grid[4 * nNodes + node], grid[5 * nNodes + node], grid[6 * nNodes + node]};
        vPic = vPic + w * vn;
        dv = dv + w * (vn - vo);
        for (int a = 0; a < 3; ++a) {
          L.m[a][0] += vn[a] * gw.x;
          L.m[a][1] += vn[a] * gw.y;
          L.m[a][2] += vn[a] * gw.z;
        }
      }
  const T dt = sc.dt;
  Vec3T<T> v{T(0), T(0), T(0)};
  bool ok = true;
  for (int d = 0; d < 3; ++d) {
    v[d] = sc.alpha * (P.v[d][p] + dv[d]) + (T(1) - sc.alpha) * vPic[d];
    T x = P.x[d][p] + dt * vPic[d];
    ok = ok && hdIsFinite(x) && hdIsFinite(v[d]);
    x = x < g.lo[d] ? g.lo[d] : (x > g.hi[d] ? g.hi[d] : x);
    Q.x[d][p] = x;
    Q.v[d][p] = v[d];
  }
  Mat3T<T> F;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) F.m[a][b] = (a == b ? T(1) : T(0)) + dt * L.m[a][b];
  const T J = P.J[p] * F.det();
  Q.J[p] = J;
  Sym6T<T> sig;
  for (int k = 0; k < 6; ++k) sig.s[k] = P.s[k][p];
  T gdp = T(0);
  std::uint8_t phase = kPhaseGasified;
  if (J > T(0)) {
    const T rho = P.mass[p] / (J * P.vol0[p]);
    phase = updateStress(sig, L, dt, rho, sc.mat, gdp);
  } else {
    ok = false;  // inverted material point
  }
  for (int k = 0; k < 6; ++k) {
    Q.s[k][p] = sig.s[k];
    ok = ok && hdIsFinite(sig.s[k]);
  }
  Q.gdp[p] = gdp;
  Q.phase[p] = phase;
  const T speed = hdSqrt(dot(v, v));
  ok = ok && hdIsFinite(J) && J >= T(kMinJ) && J <= T(kMaxJ) && speed <= sc.maxSpeed;
  return {ok, speed};
}


// ------------------------------------------------------------------ host-side set-up
// (plain host functions shared by both backends; no device code below)

// Elastic P-wave speed sqrt((lambda + 2G)/rho_0) [m/s].
inline double pWaveSpeed(const GranularMaterial& m) {
  const double E = m.youngModulus, nu = m.poissonRatio;
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double G = E / (2 * (1 + nu));
  return std::sqrt((lambda + 2 * G) / m.density);
}

template <typename T>
inline ConstitutiveConst<T> makeConstitutiveConst(const GranularMaterial& m) {
  const double E = m.youngModulus, nu = m.poissonRatio;
  ConstitutiveConst<T> c;
  c.lambda = static_cast<T>(E * nu / ((1 + nu) * (1 - 2 * nu)));
  c.G = static_cast<T>(E / (2 * (1 + nu)));
  c.muS = static_cast<T>(m.muS);
  c.mu2 = static_cast<T>(m.mu2);
  c.xi = static_cast<T>(m.I0 / (m.grainDiameter * std::sqrt(m.solidDensity)));
  c.rhoC = static_cast<T>(m.criticalDensity > 0 ? m.criticalDensity : m.density);
  return c;
}

// massEps: nodal mass below which a node counts as empty [kg].
template <typename T>
inline GridConst<T> makeGridConst(const MpmParams& prm, double massEps) {
  GridConst<T> g;
  g.dx = static_cast<T>(prm.dx);
  g.invDx = static_cast<T>(1.0 / prm.dx);
  for (int d = 0; d < 3; ++d) {
    g.origin[d] = static_cast<T>(prm.origin[d]);
    g.cells[d] = prm.cells[d];
    g.nodes[d] = prm.cells[d] + 1;
    g.gravity[d] = static_cast<T>(prm.gravity[d]);
    g.lo[d] = static_cast<T>(prm.origin[d] + kWallLayer * prm.dx);
    g.hi[d] = static_cast<T>(prm.origin[d] + (prm.cells[d] - kWallLayer) * prm.dx);
  }
  for (int w = 0; w < 6; ++w) g.wallFriction[w] = static_cast<T>(prm.walls[w].friction);
  g.massEps = static_cast<T>(massEps);
  return g;
}

// Blow-up threshold on particle speeds: 1e3 times the elastic wave speed [m/s].
inline double blowUpSpeed(const MpmParams& prm) { return 1e3 * pWaveSpeed(prm.material); }

// Checks a particle set against the grid before it is handed to a backend: consistent array
// sizes, positive mass and volume, J > 0, finite values, every particle inside the admissible
// box [origin + kWallLayer dx, origin + (cells - kWallLayer) dx] per axis. Returns the mean
// particle mass (used for the empty-node threshold). Throws ParameterError naming the field.
inline double validateParticles(const MpmParams& prm, const ParticleSet& ps) {
  const std::size_t n = ps.size();
  auto need = [&](const char* name, std::size_t got, std::size_t per) {
    if (got != per * n) {
      std::ostringstream os;
      os << per << " x numParticles = " << per * n << " values";
      throwParameter(std::string("ParticleSet.") + name + ".size()", got, "", os.str());
    }
  };
  need("x", ps.x.size(), 3);
  need("v", ps.v.size(), 3);
  need("stress", ps.stress.size(), 6);
  need("volume0", ps.volume0.size(), 1);
  need("J", ps.J.size(), 1);
  if (!ps.gammaDotP.empty()) need("gammaDotP", ps.gammaDotP.size(), 1);
  if (!ps.phase.empty()) need("phase", ps.phase.size(), 1);
  if (!ps.fext.empty()) need("fext", ps.fext.size(), 3);
  double sum = 0;
  for (std::size_t p = 0; p < n; ++p) {
    const std::string id = "[" + std::to_string(p) + "]";
    if (!(ps.mass[p] > 0) || !std::isfinite(ps.mass[p])) throwParameter("mass" + id, ps.mass[p], "kg", "finite and > 0");
    if (!(ps.volume0[p] > 0) || !std::isfinite(ps.volume0[p]))
      throwParameter("volume0" + id, ps.volume0[p], "m^3", "finite and > 0");
    if (!(ps.J[p] > 0) || !std::isfinite(ps.J[p])) throwParameter("J" + id, ps.J[p], "", "finite and > 0");
    for (int d = 0; d < 3; ++d) {
      const double lo = prm.origin[d] + kWallLayer * prm.dx, hi = prm.origin[d] + (prm.cells[d] - kWallLayer) * prm.dx;
      const double x = ps.x[3 * p + d];
      if (!(x >= lo && x <= hi)) {
        std::ostringstream os;
        os << "in [" << lo << ", " << hi << "] m (the grid box less its " << kWallLayer << "-cell wall layers)";
        throwParameter("particle x" + id + "[" + std::to_string(d) + "]", x, "m", os.str());
      }
      if (!std::isfinite(ps.v[3 * p + d])) throwParameter("v" + id, ps.v[3 * p + d], "m/s", "finite");
    }
    for (int k = 0; k < 6; ++k)
      if (!std::isfinite(ps.stress[6 * p + k])) throwParameter("stress" + id, ps.stress[6 * p + k], "Pa", "finite");
    sum += ps.mass[p];
  }
  return n ? sum / static_cast<double>(n) : 1.0;
}

}  // namespace mpm
}  // namespace mpmsdem
