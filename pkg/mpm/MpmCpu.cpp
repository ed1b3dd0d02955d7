#include "mpm/MpmCpu.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace mpm {

void MpmCpu::State::resize(std::size_t n) {
  for (auto& a : x) a.assign(n, 0.0);
  for (auto& a : v) a.assign(n, 0.0);
  for (auto& a : s) a.assign(n, 0.0);
  J.assign(n, 1.0);
  gdp.assign(n, 0.0);
  phase.assign(n, 0);
}

MpmCpu::MpmCpu(const MpmParams& params)
    : params_(params),
      grid_(makeGridConst<double>(params, 0.0)),
      mat_(makeConstitutiveConst<double>(params.material)),
      maxSpeedAllowed_(blowUpSpeed(params)) {
  nNodes_ = grid_.nodes[0] * grid_.nodes[1] * grid_.nodes[2];
  nodes_.assign(static_cast<std::size_t>(kGridComponents) * nNodes_, 0.0);
  for (int d = 0; d < 3; ++d) blocks_[d] = params.cells[d] / 3 + 1;
  for (int bx = 0; bx < blocks_[0]; ++bx)
    for (int by = 0; by < blocks_[1]; ++by)
      for (int bz = 0; bz < blocks_[2]; ++bz)
        colourBlocks_[(bx & 1) * 4 + (by & 1) * 2 + (bz & 1)].push_back((bx * blocks_[1] + by) * blocks_[2] + bz);
  blockStart_.assign(static_cast<std::size_t>(blocks_[0]) * blocks_[1] * blocks_[2] + 1, 0);
}

void MpmCpu::setParticles(const ParticleSet& ps) {
  const double meanMass = validateParticles(params_, ps);
  grid_.massEps = 1e-12 * meanMass;
  n_ = ps.size();
  for (auto& st : state_) st.resize(n_);
  cur_ = 0;
  State& s = state_[0];
  mass_ = ps.mass;
  vol0_ = ps.volume0;
  maxSpeed_ = 0;
  for (std::size_t p = 0; p < n_; ++p) {
    for (int d = 0; d < 3; ++d) {
      s.x[d][p] = ps.x[3 * p + d];
      s.v[d][p] = ps.v[3 * p + d];
    }
    for (int k = 0; k < 6; ++k) s.s[k][p] = ps.stress[6 * p + k];
    s.J[p] = ps.J[p];
    s.gdp[p] = ps.gammaDotP.empty() ? 0.0 : ps.gammaDotP[p];
    s.phase[p] = ps.phase.empty() ? static_cast<std::uint8_t>(kPhaseElastic) : ps.phase[p];
    const double sp = std::sqrt(s.v[0][p] * s.v[0][p] + s.v[1][p] * s.v[1][p] + s.v[2][p] * s.v[2][p]);
    maxSpeed_ = std::max(maxSpeed_, sp);
  }
  hasFext_ = false;
  if (!ps.fext.empty()) setExternalForces(ps.fext);
  order_.assign(n_, 0);
  blockOf_.assign(n_, 0);
}

void MpmCpu::getParticles(ParticleSet& out) {
  const State& s = state_[cur_];
  out.x.resize(3 * n_);
  out.v.resize(3 * n_);
  out.stress.resize(6 * n_);
  out.mass = mass_;
  out.volume0 = vol0_;
  out.J = s.J;
  out.gammaDotP = s.gdp;
  out.phase = s.phase;
  out.fext.assign(3 * n_, 0.0);
  for (std::size_t p = 0; p < n_; ++p) {
    for (int d = 0; d < 3; ++d) {
      out.x[3 * p + d] = s.x[d][p];
      out.v[3 * p + d] = s.v[d][p];
      if (hasFext_) out.fext[3 * p + d] = fext_[d][p];
    }
    for (int k = 0; k < 6; ++k) out.stress[6 * p + k] = s.s[k][p];
  }
}

void MpmCpu::setExternalForces(const std::vector<double>& f) {
  if (f.size() != 3 * n_) {
    std::ostringstream os;
    os << "3 x numParticles = " << 3 * n_ << " values";
    throwParameter("externalForces.size()", f.size(), "", os.str());
  }
  for (int d = 0; d < 3; ++d) fext_[d].resize(n_);
  for (std::size_t p = 0; p < n_; ++p) {
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(f[3 * p + d])) throwParameter("externalForces[" + std::to_string(3 * p + d) + "]", f[3 * p + d], "N", "finite");
      fext_[d][p] = f[3 * p + d];
    }
  }
  hasFext_ = true;
}

ParticleView MpmCpu::openForceBuffer() {
  ParticleView v;
  v.precision = Precision::Double;
  v.device = false;
  v.n = n_;
  const State& s = state_[cur_];
  for (int d = 0; d < 3; ++d) {
    fext_[d].assign(n_, 0.0);
    v.x[d] = s.x[d].data();
    v.v[d] = s.v[d].data();
    v.force[d] = fext_[d].data();
  }
  v.mass = mass_.data();
  v.volume0 = vol0_.data();
  v.J = s.J.data();
  hasFext_ = true;
  return v;
}

double MpmCpu::stableTimeStep() { return params_.cfl * params_.dx / (pWaveSpeed(params_.material) + maxSpeed_); }

std::size_t MpmCpu::memoryBytes() const {
  std::size_t b = 0;
  auto add = [&b](const auto& v) { b += v.capacity() * sizeof(typename std::decay_t<decltype(v)>::value_type); };
  for (const auto& st : state_) {
    for (const auto& a : st.x) add(a);
    for (const auto& a : st.v) add(a);
    for (const auto& a : st.s) add(a);
    add(st.J);
    add(st.gdp);
    add(st.phase);
  }
  add(mass_);
  add(vol0_);
  for (const auto& a : fext_) add(a);
  add(nodes_);
  add(blockStart_);
  add(order_);
  add(blockOf_);
  for (const auto& c : colourBlocks_) add(c);
  return b;
}

ParticleIn<double> MpmCpu::input() const {
  const State& s = state_[cur_];
  ParticleIn<double> in;
  for (int d = 0; d < 3; ++d) {
    in.x[d] = s.x[d].data();
    in.v[d] = s.v[d].data();
    in.fext[d] = hasFext_ ? fext_[d].data() : nullptr;
  }
  for (int k = 0; k < 6; ++k) in.s[k] = s.s[k].data();
  in.J = s.J.data();
  in.mass = mass_.data();
  in.vol0 = vol0_.data();
  return in;
}

ParticleOut<double> MpmCpu::output() {
  State& s = state_[1 - cur_];
  ParticleOut<double> out;
  for (int d = 0; d < 3; ++d) {
    out.x[d] = s.x[d].data();
    out.v[d] = s.v[d].data();
  }
  for (int k = 0; k < 6; ++k) out.s[k] = s.s[k].data();
  out.J = s.J.data();
  out.gdp = s.gdp.data();
  out.phase = s.phase.data();
  return out;
}

void MpmCpu::scatter(double dt, const ParticleIn<double>& in) {
  const long n = static_cast<long>(n_);
  const std::size_t nBlocks = blockStart_.size() - 1;
  // Bin the particles by the 3x3x3 block of their stencil base node.
#pragma omp parallel for schedule(static)
  for (long p = 0; p < n; ++p) {
    int b[3];
    for (int d = 0; d < 3; ++d) {
      const double g = (in.x[d][p] - grid_.origin[d]) * grid_.invDx;
      b[d] = static_cast<int>(std::floor(g - 0.5)) / 3;  // base >= 1 inside the admissible box
    }
    blockOf_[p] = (b[0] * blocks_[1] + b[1]) * blocks_[2] + b[2];
  }
  std::fill(blockStart_.begin(), blockStart_.end(), 0);
  for (long p = 0; p < n; ++p) ++blockStart_[blockOf_[p] + 1];
  for (std::size_t b = 0; b < nBlocks; ++b) blockStart_[b + 1] += blockStart_[b];
  {
    std::vector<int> fill(blockStart_.begin(), blockStart_.end() - 1);
    for (long p = 0; p < n; ++p) order_[fill[blockOf_[p]]++] = static_cast<int>(p);
  }
  double* gridData = nodes_.data();
  const int nN = nNodes_;
  auto add = [gridData, nN](int node, double m, const Vec3T<double>& pOld, const Vec3T<double>& pNew) {
    gridData[node] += m;
    gridData[nN + node] += pOld.x;
    gridData[2 * nN + node] += pOld.y;
    gridData[3 * nN + node] += pOld.z;
    gridData[4 * nN + node] += pNew.x;
    gridData[5 * nN + node] += pNew.y;
    gridData[6 * nN + node] += pNew.z;
  };
  for (int c = 0; c < 8; ++c) {
    const std::vector<int>& list = colourBlocks_[c];
    const long nb = static_cast<long>(list.size());
#pragma omp parallel for schedule(dynamic, 4)
    for (long i = 0; i < nb; ++i) {
      const int b = list[i];
      auto addLocal = add;
      for (int q = blockStart_[b]; q < blockStart_[b + 1]; ++q) p2gParticle(order_[q], in, grid_, dt, addLocal);
    }
  }
}

void MpmCpu::step(double dt) {
  if (steps_ % 100 == 0) checkTimeStep(dt);
  const ParticleIn<double> in = input();
  const ParticleOut<double> out = output();
  const long nN = nNodes_;
  double* gridData = nodes_.data();
#pragma omp parallel for schedule(static)
  for (long i = 0; i < kGridComponents * nN; ++i) gridData[i] = 0.0;
  scatter(dt, in);
  const GridConst<double> g = grid_;
  if (hooks_.empty()) {
#pragma omp parallel for schedule(static)
    for (long i = 0; i < nN; ++i) gridNodeUpdate(static_cast<int>(i), gridData, nNodes_, g, dt);
  } else {
#pragma omp parallel for schedule(static)
    for (long i = 0; i < nN; ++i) gridNodeVelocity(static_cast<int>(i), gridData, nNodes_, g, dt);
    GridView view = gridViewFrame(dt);
    view.precision = Precision::Double;
    view.device = false;
    view.mass = gridData;
    for (int d = 0; d < 3; ++d) view.v[d] = gridData + (4 + d) * nN;
    applyGridHooks(view);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < nN; ++i) gridNodeWalls(static_cast<int>(i), gridData, nNodes_, g);
  }

  StepConst<double> sc;
  sc.dt = dt;
  sc.alpha = params_.flipAlpha;
  sc.maxSpeed = maxSpeedAllowed_;
  sc.mat = mat_;
  const long n = static_cast<long>(n_);
  long firstBad = n;
  double vmax = 0;
#pragma omp parallel for schedule(static) reduction(min : firstBad) reduction(max : vmax)
  for (long p = 0; p < n; ++p) {
    const G2PResult<double> r = g2pParticle(static_cast<int>(p), in, out, gridData, nNodes_, g, sc);
    if (!r.ok && p < firstBad) firstBad = p;
    if (r.speed > vmax) vmax = r.speed;
  }
  if (firstBad < n) {
    const long p = firstBad;
    std::ostringstream os;
    os << "MPM step " << steps_ + 1 << " (t = " << time_ + dt << " s): particle " << p
       << " has a non-finite state, a speed above " << maxSpeedAllowed_
       << " m/s (1e3 x P-wave speed) or a volume ratio J outside [" << kMinJ << ", " << kMaxJ
       << "] (crushed or torn apart: no granular material does that; a step too large for the loading?): x = ("
       << out.x[0][p] << ", " << out.x[1][p] << ", " << out.x[2][p] << ") m, v = (" << out.v[0][p] << ", "
       << out.v[1][p] << ", " << out.v[2][p] << ") m/s, J = " << out.J[p]
       << ". The particle state is kept at the start of this step.";
    throw RuntimeFailure(os.str());
  }
  cur_ = 1 - cur_;
  maxSpeed_ = vmax;
  hasFext_ = false;
  time_ += dt;
  ++steps_;
}

}  // namespace mpm
}  // namespace mpmsdem
