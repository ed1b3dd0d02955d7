// Material point against a LevelSet body (LevelSetKernelsCommon.hpp, MpLevelSetCoupling): the
// interpolated distance and normal of analytic sphere and cube grids against hand-derived
// values, the Eq 10 force they give, the grid's linear continuation, the impulse balance of
// a flow on a body (Eqs 17–18), float against double, the too-coarse refusal, bad input; the
// zero level set drawn for ParaView.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "../mpm/GranularColumn.hpp"
#include "common/Error.hpp"
#include "coupling/LevelSetSurface.hpp"
#include "coupling/MpLevelSetCoupling.hpp"
#include "mpm/Seeding.hpp"

using namespace mpmsdem;
using namespace mpmsdem::coupling;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A grid of phi(x) at nodes min + (i, j, k) h.
LevelSetGrid analyticGrid(const Vec3& min, double h, int n, const std::function<double(const Vec3&)>& phi) {
  LevelSetGrid g;
  g.min = min;
  g.spacing = h;
  g.nGP = {n, n, n};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) g.dist.push_back(phi(min + h * Vec3(i, j, k)));
  return g;
}

double sphereDistance(const Vec3& x, double r) { return x.norm() - r; }

// Signed distance to the cube [-a, a]^3.
double cubeDistance(const Vec3& x, double a) {
  const Vec3 q = x.cwiseAbs() - Vec3::Constant(a);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

sdem::BarrierPhys physics(double kc = 1e4, double mu = 0.3) {
  sdem::BarrierPhys p;
  p.barrierStiffness = kc;
  p.friction = mu;
  p.poisson = 0.3;
  p.normalDamping = 0;
  p.tangentialDamping = 0;
  return p;
}

// Eq 10 as a force, written out: F_n = -k_c delta [2 ln((R - delta)/R) - R/(R - delta) + 1].
double eq10(double kc, double R, double delta) {
  return -kc * delta * (2 * std::log((R - delta) / R) - R / (R - delta) + 1);
}

// One material point at rest, as a solver's particle view.
struct OnePoint {
  double x[3], v[3] = {0, 0, 0}, mass, vol0, f[3] = {0, 0, 0};
  OnePoint(const Vec3& pos, double volume0) : mass(1600 * volume0), vol0(volume0) {
    for (int d = 0; d < 3; ++d) x[d] = pos[d];
  }
  mpm::ParticleView view() {
    mpm::ParticleView w;
    w.n = 1;
    for (int d = 0; d < 3; ++d) {
      w.x[d] = &x[d];
      w.v[d] = &v[d];
      w.force[d] = &f[d];
    }
    w.mass = &mass;
    w.volume0 = &vol0;
    return w;
  }
};

// Eight points per cell of a 0.01 m grid (Eq 13): R_p0 = (3 V0 / 4 pi)^(1/3) = 3.1018 mm.
constexpr double kDx = 0.01;
const double kV0 = kDx * kDx * kDx / 8;
const double kRp = std::cbrt(3 * kV0 / (4 * kPi));

// Glass beads on a 20-cell cube of the 0.01 m grid, without gravity.
mpm::MpmParams beadsWithoutGravity() { return mpm::testing_scenes::tableOneBeads({20, 20, 20}, kDx, {0, 0, 0}); }

// A fixed body at the origin (or pos/ori), one point at x; the contact it makes.
MpContactRecord touch(const LevelSetGrid& g, const Vec3& x, const Vec3& pos = Vec3::Zero(),
                      const Quat& ori = Quat::Identity(), double* particleForce = nullptr) {
  MpLevelSetCoupling c;
  c.addBody(7, g, physics());
  c.setState(0, pos, ori, Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, true);
  OnePoint p(x, kV0);
  c.computeForces(p.view(), 1e-5, 0.0, 0.5, kDx);
  const std::vector<MpContactRecord> r = c.contacts();
  EXPECT_EQ(r.size(), 1u);
  if (particleForce)
    for (int d = 0; d < 3; ++d) particleForce[d] = p.f[d];
  return r.empty() ? MpContactRecord() : r[0];
}

}  // namespace

TEST(LevelSetCoupling, ParticleRadiusIsEq13) { EXPECT_NEAR(kRp, 3.1018e-3, 1e-7); }

// Sphere r = 0.05 m on a grid whose nodes sit at +-h/2, +-3h/2, ...: a point on the x axis is
// at the centre of its cell's y-z square, so the four corners of each x-plane share
// y^2 + z^2 = h^2 / 2: the gradient has no y or z part (normal exactly +x) and along x phi is
// interpolated linearly between sqrt(x_i^2 + h^2/2) - r at the two planes x_0, x_1.
TEST(LevelSetCoupling, SphereOverlapForceAndNormal) {
  const double r = 0.05, h = 0.0025;
  const LevelSetGrid g =
      analyticGrid(Vec3::Constant(-24.5 * h), h, 50, [r](const Vec3& x) { return sphereDistance(x, r); });
  const Vec3 x(0.052, 0, 0);  // 2 mm outside the sphere
  // cell planes x_0 = 0.05125, x_1 = 0.05375 (node i = 45, 46), fraction u = 0.3
  const double x0 = -24.5 * h + 45 * h, x1 = x0 + h, u = (x[0] - x0) / h;
  EXPECT_NEAR(u, 0.3, 1e-12);
  const double d = (1 - u) * std::sqrt(x0 * x0 + h * h / 2) + u * std::sqrt(x1 * x1 + h * h / 2) - r;
  // the interpolant sees the sphere h^2 / (4 x) = 30 um farther than it is, to 1 %
  EXPECT_GT(d - 0.002, 0.99 * h * h / (4 * 0.052));
  EXPECT_LT(d - 0.002, 1.01 * h * h / (4 * 0.052));
  double fp[3];
  const MpContactRecord c = touch(g, x, Vec3::Zero(), Quat::Identity(), fp);
  const double delta = kRp - d;  // 1.072 mm
  EXPECT_NEAR(c.overlap, delta, 1e-15);
  const double fn = eq10(1e4, kRp, delta);
  EXPECT_NEAR(fn, 14.744, 0.001);
  // a third above its leading term 3 k_c delta^2 / R (11.11 N) at delta = 0.35 R_p0
  EXPECT_NEAR(fn / (3 * 1e4 * delta * delta / kRp), 1.327, 0.002);
  EXPECT_NEAR(c.normalForce, fn, 1e-12 * fn);
  // (the nodes at +-h/2 are min + j h, equal in magnitude to round-off only)
  EXPECT_NEAR(c.normal[0], 1.0, 1e-14);
  EXPECT_NEAR(c.normal[1], 0.0, 1e-12);
  EXPECT_NEAR(c.normal[2], 0.0, 1e-12);
  // the body takes -F at the point midway between its surface and the point's sphere
  EXPECT_NEAR(c.force[0], -fn, 1e-12 * fn);
  EXPECT_NEAR(fp[0], fn, 1e-12 * fn);
  EXPECT_NEAR(c.point[0], x[0] - 0.5 * (d + kRp), 1e-15);
}

// Cube of half-size a = 0.05 m with its faces on grid planes. Before a face (all eight
// corners of the cell in the face's region, where phi = x - a is linear) the interpolation is
// exact; in the cell beyond a corner, phi = |x - corner| sampled at the cell's corners
// (0, h, h sqrt 2, h sqrt 3) gives at fraction 0.4 along the diagonal
// h (3 0.4 0.6^2 + 3 sqrt2 0.4^2 0.6 + sqrt3 0.4^3) = 0.95014 h instead of 0.69282 h: the
// corner looks rounded by 0.2573 h, the error the spacing rule bounds (levelSetSpacingLimit).
TEST(LevelSetCoupling, CubeFaceExactCornerRounded) {
  const double a = 0.05, h = 0.0025;
  const LevelSetGrid g = analyticGrid(Vec3::Constant(-0.06), h, 49, [a](const Vec3& x) { return cubeDistance(x, a); });
  {
    const Vec3 x(a + 0.0015, 0.0123, -0.0311);  // 1.5 mm before the +x face, off the grid nodes
    const MpContactRecord c = touch(g, x);
    const double delta = kRp - 0.0015;
    EXPECT_NEAR(c.overlap, delta, 1e-15);
    EXPECT_NEAR(c.normalForce, eq10(1e4, kRp, delta), 1e-11 * eq10(1e4, kRp, delta));
    EXPECT_NEAR(c.normal[0], 1.0, 1e-14);
    EXPECT_NEAR(c.normal[1], 0.0, 1e-12);
    EXPECT_NEAR(c.normal[2], 0.0, 1e-12);
  }
  {
    const double s = 0.4 * h;
    const Vec3 x = Vec3::Constant(a + s);
    const double d = h * (3 * 0.4 * 0.36 + 3 * std::sqrt(2.0) * 0.16 * 0.6 + std::sqrt(3.0) * 0.064);
    EXPECT_NEAR(d / h, 0.95014, 1e-5);
    EXPECT_NEAR((d - std::sqrt(3.0) * s) / h, 0.25732, 1e-5);
    const MpContactRecord c = touch(g, x);
    EXPECT_NEAR(c.overlap, kRp - d, 1e-15);
    EXPECT_NEAR(c.normalForce, eq10(1e4, kRp, kRp - d), 1e-11 * eq10(1e4, kRp, kRp - d));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(c.normal[k], 1 / std::sqrt(3.0), 1e-12);
  }
}

// The body frame: phi is read at ori^-1 (x - pos), the normal turned back to the world.
TEST(LevelSetCoupling, MovedAndTurnedBody) {
  const double a = 0.05, h = 0.0025;
  const LevelSetGrid g = analyticGrid(Vec3::Constant(-0.06), h, 49, [a](const Vec3& x) { return cubeDistance(x, a); });
  const Vec3 pos(1.0, -2.0, 0.5);
  const Quat ori(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  const Vec3 local(a + 0.0015, 0.0123, -0.0311);
  const MpContactRecord c = touch(g, pos + ori * local, pos, ori);
  EXPECT_NEAR(c.overlap, kRp - 0.0015, 1e-14);
  EXPECT_LT((c.normal - ori * Vec3::UnitX()).norm(), 1e-12);
}

// Beyond the grid's box phi continues as phi(c) + |x - c| from the nearest point c of the box:
// YADE's grids end about a cell past the surface, closer than the barrier's reach. Grid to
// 0.051 m around a cube of half-size 0.05 m (0.32 R_p0 of margin): a point 2.5 mm before the
// face, 1.5 mm outside the box, touches with phi = 1 mm + 1.5 mm; beyond the box's edge, where
// YADE's box grids are flat along the side (max(|x_i| - a) there: no gradient to carry out),
// the continuation still grows with the distance from the box, and a point at 2.9 mm along x
// and 2.9 mm along y from the edge (phi = 1 mm + 1.9 sqrt2 mm = 3.69 mm > R_p0) does not touch.
TEST(LevelSetCoupling, ContinuationBeyondTheGrid) {
  const double a = 0.05, h = 0.001;
  const LevelSetGrid g = analyticGrid(Vec3::Constant(-0.051), h, 103, [a](const Vec3& x) { return cubeDistance(x, a); });
  const MpContactRecord c = touch(g, Vec3(a + 0.0025, 0.01, 0.0));
  EXPECT_NEAR(c.overlap, kRp - 0.0025, 1e-14);
  EXPECT_NEAR(c.normal[0], 1.0, 1e-12);
  auto chebyshev = [a](const Vec3& x) { return (x.cwiseAbs() - Vec3::Constant(a)).maxCoeff(); };
  const LevelSetGrid flat = analyticGrid(Vec3::Constant(-0.051), h, 103, chebyshev);
  MpLevelSetCoupling cl;
  cl.addBody(4, flat, physics());
  cl.setState(0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, true);
  OnePoint far(Vec3(a + 0.0029, a + 0.0029, 0.0), kV0);
  cl.computeForces(far.view(), 1e-5, 0.0, 0.5, kDx);
  EXPECT_EQ(cl.contactCount(0), 0);
  EXPECT_TRUE(std::isnan(cl.firstContact(0)));  // not touched yet
  // nearer, the same point touches along the diagonal: phi = 1 mm + 1.1 sqrt2 mm = 2.556 mm,
  // in the step from 2e-5 s, the body's first contact
  OnePoint near(Vec3(a + 0.0021, a + 0.0021, 0.0), kV0);
  cl.computeForces(near.view(), 1e-5, 2e-5, 0.5, kDx);
  EXPECT_EQ(cl.firstContact(0), 2e-5);
  cl.computeForces(near.view(), 1e-5, 3e-5, 0.5, kDx);
  EXPECT_EQ(cl.firstContact(0), 2e-5);  // set once
  const std::vector<MpContactRecord> r = cl.contacts();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].overlap, kRp - (0.001 + 0.0011 * std::sqrt(2.0)), 1e-14);
  EXPECT_NEAR(r[0].normal[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(r[0].normal[1], std::sqrt(0.5), 1e-12);
}

// A block of points pressed into a sphere: the force on the body is minus the sum of the
// forces the particles take (Eqs 17–18), per step, to round-off; the particle forces reach the
// solver's buffer on top of what was there (extendForceBuffer).
TEST(LevelSetCoupling, ImpulseBalanceWithSolver) {
  const mpm::MpmParams prm = beadsWithoutGravity();
  mpm::ParticleSet ps;
  // a slab whose lowest points sit 1 mm into the barrier of a sphere of radius 0.05 at (0.1, 0.1, 0.05)
  mpm::seedBox(prm, {0.07, 0.07, 0.1}, {0.13, 0.13, 0.13}, {2, 2, 2}, ps);
  double zmin = 1;
  for (std::size_t p = 0; p < ps.size(); ++p) zmin = std::min(zmin, ps.x[3 * p + 2]);
  for (std::size_t p = 0; p < ps.size(); ++p) {
    ps.x[3 * p + 2] += 0.1 + kRp - 0.001 - zmin;
    ps.v[3 * p + 0] = 0.3;  // sliding along x: friction too
  }
  auto solver = mpm::makeSolver(prm);
  solver->setParticles(ps);
  MpLevelSetCoupling c;
  c.addBody(3, analyticGrid(Vec3::Constant(-0.06), 0.0025, 49, [](const Vec3& x) { return sphereDistance(x, 0.05); }),
            physics(1e4, 0.4));
  const Vec3 pos(0.1, 0.1, 0.05);
  const double dt = 1e-5;
  for (int step = 0; step < 3; ++step) {
    c.setState(0, pos, Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, false);
    mpm::ParticleView v = solver->openForceBuffer();
    for (std::size_t p = 0; p < v.n; ++p) static_cast<double*>(v.force[2])[p] = -1e-3;  // a first coupling's
    c.computeForces(solver->extendForceBuffer(), dt, solver->time(), 0.5, kDx);
    ASSERT_GE(c.contactCount(0), 5);
    mpm::ParticleSet out;
    solver->getParticles(out);
    Vec3 sum = Vec3::Zero();
    for (std::size_t p = 0; p < out.size(); ++p)
      for (int d = 0; d < 3; ++d) sum[d] += out.fext[3 * p + d] + (d == 2 ? 1e-3 : 0.0);
    const Vec3 f = c.force(0);
    EXPECT_GT(f.norm(), 0.01);
    EXPECT_LT((sum + f).norm(), 1e-13 * f.norm());
    EXPECT_LT(f[2], -0.9 * f.norm());  // pressed down, the slab lying on it
    solver->step(dt);
  }
}

namespace {

// A slab sliding over a turning sphere (4,704 points: two chunks of the CPU loop), its lowest
// layer 1 mm into the barrier, three steps; each step's contacts made twice, by two couplings of
// the same body, the second adding to the first's forces (extendForceBuffer): the body's force,
// torque and contacts of the second, and the particles after the steps. The sphere's centre lies
// off the points' lattice: a point on a plane of the level-set grid has a normal that depends on
// which cell the rounding of its coordinate picks (the trilinear gradient jumps across a cell
// face), so float and double would part there by more than their round-off.
struct SlabRun {
  Vec3 force, torque;
  std::vector<double> x;
  std::vector<MpContactRecord> contacts;
  std::vector<long long> keys;
  std::vector<double> xi;
};

SlabRun slabOnSphere(mpm::Backend backend, mpm::Precision precision) {
  const mpm::MpmParams prm = beadsWithoutGravity();
  mpm::ParticleSet ps;
  mpm::seedBox(prm, {0.03, 0.03, 0.1}, {0.17, 0.17, 0.13}, {2, 2, 2}, ps);
  EXPECT_GT(ps.size(), 4096u);
  for (std::size_t p = 0; p < ps.size(); ++p) {
    ps.x[3 * p + 2] -= 0.0025 + 0.001 - kRp;  // the lowest layer 1 mm into the sphere's barrier
    ps.v[3 * p + 0] = 0.3;
  }
  const LevelSetGrid g =
      analyticGrid(Vec3::Constant(-0.06), 0.0025, 49, [](const Vec3& x) { return sphereDistance(x, 0.05); });
  auto solver = mpm::makeSolver(prm, backend, precision);
  solver->setParticles(ps);
  MpLevelSetCoupling first, second;
  for (MpLevelSetCoupling* c : {&first, &second}) {
    c->addBody(3, g, physics(1e4, 0.4));
    c->setState(0, Vec3(0.1011, 0.1007, 0.05), Quat::Identity(), Vec3::Zero(), Vec3(0, 0, 1), 1.0, 1e-3, false);
  }
  for (int step = 0; step < 3; ++step) {
    first.computeForces(solver->openForceBuffer(), 1e-5, 0.0, 0.5, kDx);
    second.computeForces(solver->extendForceBuffer(), 1e-5, 0.0, 0.5, kDx);
    solver->step(1e-5);
  }
  SlabRun r{second.force(0), second.torque(0), {}, second.contacts(), {}, {}};
  EXPECT_GT(second.contactCount(0), 5);
  mpm::ParticleSet out;
  solver->getParticles(out);
  r.x = out.x;
  second.pullHistories();
  r.keys = second.historyKeys();
  r.xi = second.historyXi();
  return r;
}

}  // namespace

// Contacts are summed per body in particle order, chunk by chunk: 1 and 2 OpenMP threads give the
// same forces, torques and particle positions to the bit.
TEST(LevelSetCoupling, ThreadCountIndependent) {
  const int before = omp_get_max_threads();
  SlabRun run[2];
  for (int k = 0; k < 2; ++k) {
    omp_set_num_threads(k + 1);
    run[k] = slabOnSphere(mpm::Backend::Cpu, mpm::Precision::Double);
  }
  omp_set_num_threads(before);
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(run[0].force[d], run[1].force[d]);
    EXPECT_EQ(run[0].torque[d], run[1].torque[d]);
  }
  EXPECT_EQ(run[0].x, run[1].x);  // the particles after three steps
}

namespace {

// `run` against `ref` on the same slab: the body's force and torque to `tol` of them, the particles
// to `dxTol` [m], the same contacts (by particle) and history keys, each history slot's elastic
// tangential force to `tol` of the largest one.
void expectSlabsAgree(const SlabRun& run, const SlabRun& ref, double tol, double dxTol, const char* what) {
  std::printf("LevelSet slab, %s: force %.3e of %.4g N, torque %.3e of %.4g N m\n", what,
              (run.force - ref.force).norm(), ref.force.norm(), (run.torque - ref.torque).norm(), ref.torque.norm());
  EXPECT_LT((run.force - ref.force).norm(), tol * ref.force.norm()) << what;
  EXPECT_LT((run.torque - ref.torque).norm(), tol * ref.torque.norm()) << what;
  ASSERT_EQ(run.x.size(), ref.x.size()) << what;
  double dx = 0;
  for (std::size_t k = 0; k < ref.x.size(); ++k) dx = std::max(dx, std::abs(run.x[k] - ref.x[k]));
  EXPECT_LT(dx, dxTol) << what;
  ASSERT_EQ(run.contacts.size(), ref.contacts.size()) << what;
  for (std::size_t k = 0; k < ref.contacts.size(); ++k) EXPECT_EQ(run.contacts[k].particle, ref.contacts[k].particle);
  EXPECT_EQ(run.keys, ref.keys) << what;
  ASSERT_EQ(run.xi.size(), ref.xi.size()) << what;
  const auto slot = [](const std::vector<double>& xi, std::size_t k) { return Vec3(xi[3 * k], xi[3 * k + 1], xi[3 * k + 2]); };
  double largest = 0, worst = 0;
  for (std::size_t k = 0; 3 * k < ref.xi.size(); ++k) {
    largest = std::max(largest, slot(ref.xi, k).norm());
    worst = std::max(worst, (slot(run.xi, k) - slot(ref.xi, k)).norm());
  }
  std::printf("LevelSet slab, %s: particles %.3e m, tangential history %.3e of %.4g N\n", what, dx, worst, largest);
  EXPECT_GT(largest, 0) << what;  // the slab slid: some contact carries a tangential force
  EXPECT_LT(worst, tol * largest) << what;
}

}  // namespace

// Float against double on the same slab: float round-off alone. Measured on the CPU (2-core x86_64):
// force 2.8e-6, torque 1.3e-6, tangential history 4.5e-6 of the largest, particles 2.3e-8 m;
// the bounds are ten to twenty times that, for the CPU's float run and the device's (which
// repeats the CPU's float arithmetic, its sums in another order).
constexpr double kFloatTol = 5e-5, kFloatDx = 5e-7;

TEST(LevelSetCoupling, FloatSlabAgreesWithDouble) {
  expectSlabsAgree(slabOnSphere(mpm::Backend::Cpu, mpm::Precision::Float),
                   slabOnSphere(mpm::Backend::Cpu, mpm::Precision::Double), kFloatTol, kFloatDx,
                   "cpu-float against cpu-double");
}

// The CUDA path (the SDEM backend's kernel over coupleParticleLevelSets, its ordered sums, the
// device's extendForceBuffer) against the CPU loop on the same slab: in double to 1e-9 and the
// particles to 1e-12 m (sums in another order), in float to the CPU float run's bounds.
TEST(LevelSetCoupling, CpuAndCudaAgree) {
  if (!mpm::cudaAvailable()) GTEST_SKIP() << "no CUDA device in this build/machine: CPU-vs-CUDA LevelSet check skipped";
  const SlabRun cpu = slabOnSphere(mpm::Backend::Cpu, mpm::Precision::Double);
  expectSlabsAgree(slabOnSphere(mpm::Backend::Cuda, mpm::Precision::Double), cpu, 1e-9, 1e-12,
                   "cuda-double against cpu-double");
  expectSlabsAgree(slabOnSphere(mpm::Backend::Cuda, mpm::Precision::Float), cpu, kFloatTol, kFloatDx,
                   "cuda-float against cpu-double");
}

// A float solver meets float copies of the grid and state: the same forces to float round-off.
TEST(LevelSetCoupling, FloatAgreesWithDouble) {
  const LevelSetGrid g =
      analyticGrid(Vec3::Constant(-0.06), 0.0025, 49, [](const Vec3& x) { return cubeDistance(x, 0.05); });
  const Vec3 xs[] = {Vec3(0.0515, 0.0123, -0.0311), Vec3(0.051, 0.051, 0.051), Vec3(0.0, -0.052, 0.02)};
  for (const Vec3& x : xs) {
    MpLevelSetCoupling cd, cf;
    cd.addBody(1, g, physics());
    cf.addBody(1, g, physics());
    cd.setState(0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, true);
    cf.setState(0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, true);
    OnePoint p(x, kV0);
    cd.computeForces(p.view(), 1e-5, 0.0, 0.5, kDx);
    float xf[3] = {float(x[0]), float(x[1]), float(x[2])}, vf[3] = {0, 0, 0}, mf = float(p.mass),
          v0f = float(kV0), ff[3] = {0, 0, 0};
    mpm::ParticleView w;
    w.precision = mpm::Precision::Float;
    w.n = 1;
    for (int d = 0; d < 3; ++d) {
      w.x[d] = &xf[d];
      w.v[d] = &vf[d];
      w.force[d] = &ff[d];
    }
    w.mass = &mf;
    w.volume0 = &v0f;
    cf.computeForces(w, 1e-5, 0.0, 0.5, kDx);
    ASSERT_EQ(cd.contactCount(0), 1);
    ASSERT_EQ(cf.contactCount(0), 1);
    // delta ~ 1 mm from distances ~ 0.05 m in float (eps 6e-8): 3e-9 m, a relative 1e-5 of F ~ delta^2
    EXPECT_LT((cf.force(0) - cd.force(0)).norm(), 2e-4 * cd.force(0).norm());
  }
}

TEST(LevelSetCoupling, CoarseGridRefused) {
  MpLevelSetCoupling c;
  const LevelSetGrid g =
      analyticGrid(Vec3::Constant(-0.06), 0.004, 31, [](const Vec3& x) { return sphereDistance(x, 0.05); });
  c.addBody(12, g, physics());
  c.checkResolution(0.004);  // spacing == R_p0: allowed
  try {
    c.checkResolution(kRp);
    FAIL() << "a 4 mm grid against R_p0 = 3.1 mm was accepted";
  } catch (const ParameterError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("LevelSet body 12"), std::string::npos) << m;
    EXPECT_NE(m.find("spacing 0.004 m"), std::string::npos) << m;
    EXPECT_NE(m.find("R_p0 = 0.0031"), std::string::npos) << m;
  }
  // and at the step, from the particles' own volumes
  c.setState(0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, true);
  OnePoint p(Vec3(0.3, 0, 0), kV0);
  EXPECT_THROW(c.computeForces(p.view(), 1e-5, 0.0, 0.5, kDx), ParameterError);
}

TEST(LevelSetCoupling, BadInput) {
  MpLevelSetCoupling c;
  LevelSetGrid g = analyticGrid(Vec3::Zero(), 0.001, 3, [](const Vec3& x) { return x.norm() - 0.001; });
  LevelSetGrid bad = g;
  bad.spacing = 0;
  EXPECT_THROW(c.addBody(1, bad, physics()), ParameterError);
  bad = g;
  bad.nGP[1] = 1;
  EXPECT_THROW(c.addBody(1, bad, physics()), ParameterError);
  bad = g;
  bad.dist.pop_back();
  EXPECT_THROW(c.addBody(1, bad, physics()), ParameterError);
  bad = g;
  bad.dist[4] = NAN;
  EXPECT_THROW(c.addBody(1, bad, physics()), ParameterError);
  EXPECT_THROW(c.addBody(1, g, physics(-1.0)), ParameterError);
  EXPECT_EQ(c.numBodies(), 0);
  c.addBody(1, g, physics());
  OnePoint p(Vec3(0.3, 0, 0), kV0);
  EXPECT_THROW(c.computeForces(p.view(), 1e-5, 0.0, 0.5, kDx), RuntimeFailure);  // no state set
  EXPECT_THROW(c.setState(0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 0.0, 0.0, false),
               ParameterError);
  EXPECT_THROW(c.setHistorySlots(5), ParameterError);
}

// A point whose centre reached the surface (phi <= 0) stops the step, naming point and body.
TEST(LevelSetCoupling, CentreInsideFails) {
  MpLevelSetCoupling c;
  c.addBody(9, analyticGrid(Vec3::Constant(-0.06), 0.0025, 49, [](const Vec3& x) { return sphereDistance(x, 0.05); }),
            physics());
  c.setState(0, Vec3::Zero(), Quat::Identity(), Vec3::Zero(), Vec3::Zero(), 1.0, 1e-3, true);
  OnePoint p(Vec3(0.049, 0, 0), kV0);
  try {
    c.computeForces(p.view(), 1e-5, 0.0, 0.5, kDx);
    FAIL();
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("material point 0 reached the surface of LevelSet body 9"), std::string::npos)
        << e.what();
  }
}

// ---- the zero level set as a ParaView surface (LevelSetSurface.hpp)

namespace {

// Checks that `s` is a closed surface wound consistently: every edge in exactly two triangles,
// once in each direction, and V - E + F = 2 (a sphere's topology). Returns the volume it
// encloses (divergence theorem; > 0 when the normals point out).
double closedSurfaceVolume(const io::RigidSurface& s) {
  std::map<std::pair<int, int>, int> directed;
  double volume = 0;
  for (const auto& t : s.triangles) {
    for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
    const Vec3 a(s.vertices[t[0]].data()), b(s.vertices[t[1]].data()), c(s.vertices[t[2]].data());
    volume += a.dot(b.cross(c)) / 6;
  }
  std::size_t edges = 0;
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1) << "edge " << e.first << "-" << e.second << " used " << n << " times in one direction";
    const auto back = directed.find({e.second, e.first});
    EXPECT_TRUE(back != directed.end() && back->second == 1) << "edge " << e.first << "-" << e.second << " open";
    if (e.first < e.second) ++edges;
  }
  EXPECT_EQ(static_cast<long>(s.vertices.size()) - static_cast<long>(edges) + static_cast<long>(s.triangles.size()), 2);
  return volume;
}

}  // namespace

// A sphere of radius R on a grid of spacing h: along each edge phi = |x| - R is convex, so the
// edge's linear zero lies inside the sphere by at most the chord's gap, L^2 / (8 min|x|) with L
// <= sqrt(3) h the edge's length and min|x| >= R - L: every vertex has |x| in [R - gap, R]. Every
// point of the mesh lies in a cell with an outside node, within sqrt(3) h of it: the mesh
// encloses the ball of radius R - sqrt(3) h and lies in the sphere (convex), which bound its
// volume on both sides.
TEST(LevelSetSurface, SphereIsClosedOutwardAndOnTheSphere) {
  const double R = 0.05, h = 0.01, L = std::sqrt(3.0) * h, gap = L * L / (8 * (R - L));
  const LevelSetGrid g = analyticGrid(Vec3::Constant(-0.0713), h, 15, [R](const Vec3& x) { return sphereDistance(x, R); });
  const io::RigidSurface s = levelSetSurface(g, 7);
  EXPECT_EQ(s.id, 7);
  ASSERT_GT(s.triangles.size(), 100u);
  double lowest = R;
  for (const auto& v : s.vertices) {
    const double r = Vec3(v.data()).norm();
    EXPECT_LE(r, R + 1e-15);
    EXPECT_GE(r, R - gap - 1e-15);
    lowest = std::min(lowest, r);
  }
  const double volume = closedSurfaceVolume(s);
  std::printf("sphere R %g m, h %g m: %zu vertices, %zu triangles; vertices %.3g mm below R at most (bound %.3g mm); "
              "volume / sphere's %.4f\n", R, h, s.vertices.size(), s.triangles.size(), 1e3 * (R - lowest), 1e3 * gap,
              volume / (4.0 / 3 * kPi * R * R * R));
  EXPECT_LE(volume, 4.0 / 3 * kPi * R * R * R);
  EXPECT_GE(volume, 4.0 / 3 * kPi * std::pow(R - L, 3));
}

// A cube's distance is convex too: vertices lie in the cube, within an edge's length of its
// surface, and on its faces exactly where phi is linear along the edge (both nodes over the
// same face's interior). Placed in the world, each vertex is pos + R x.
TEST(LevelSetSurface, CubeIsClosedAndPlacedByThePose) {
  const double a = 0.02, h = 0.004, L = std::sqrt(3.0) * h;
  const LevelSetGrid g = analyticGrid(Vec3::Constant(-0.0301), h, 16, [a](const Vec3& x) { return cubeDistance(x, a); });
  const io::RigidSurface s = levelSetSurface(g, 3);
  int onFace = 0;
  for (const auto& v : s.vertices) {
    const Vec3 x(v.data());
    const double phi = cubeDistance(x, a);
    EXPECT_LE(phi, 1e-15);
    EXPECT_GE(phi, -L);
    // over a face's interior, two cells from its edges: both nodes of the vertex's edge have
    // phi = |x_k| - a (k across the face), linear along it
    if ((x.cwiseAbs().array() < a - 2 * h).count() == 2) {
      EXPECT_NEAR(x.cwiseAbs().maxCoeff(), a, 1e-15);
      ++onFace;
    }
  }
  EXPECT_GT(onFace, 50);
  const double volume = closedSurfaceVolume(s);
  EXPECT_LE(volume, 8 * a * a * a);
  EXPECT_GE(volume, 8 * std::pow(a - L, 3));
  const Vec3 pos(0.3, -0.1, 0.05);
  const Mat3 R = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())).toRotationMatrix();
  const io::RigidSurface w = placedSurface(s, pos, R);
  ASSERT_EQ(w.vertices.size(), s.vertices.size());
  EXPECT_EQ(w.triangles, s.triangles);
  EXPECT_EQ(w.id, 3);
  for (std::size_t i = 0; i < s.vertices.size(); ++i)
    EXPECT_LT((Vec3(w.vertices[i].data()) - pos - R * Vec3(s.vertices[i].data())).norm(), 1e-16);
}

// phi of one sign everywhere: nothing to draw.
TEST(LevelSetSurface, NoZeroCrossingGivesNoSurface) {
  const LevelSetGrid outside = analyticGrid(Vec3::Constant(0.1), 0.01, 4, [](const Vec3& x) { return x.norm(); });
  EXPECT_TRUE(levelSetSurface(outside, 0).triangles.empty());
  const LevelSetGrid inside = analyticGrid(Vec3::Constant(0.0), 0.01, 4, [](const Vec3&) { return -1.0; });
  EXPECT_TRUE(levelSetSurface(inside, 0).vertices.empty());
}
