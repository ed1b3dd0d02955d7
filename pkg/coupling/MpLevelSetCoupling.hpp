// MpLevelSetCoupling: contact between the material points of a CPU MPM solver and rigid bodies
// given by a signed-distance grid, YADE's LevelSet bodies (contact math in
// LevelSetKernelsCommon.hpp). The bodies are moved by their owner (YADE's NewtonIntegrator): each
// step the caller sets their pose and motion, computeForces adds the points' forces into the
// solver's force buffer and sums the opposite forces per body, which the caller hands to the
// bodies. The law, the particle radius R_p0 and the force split are those of the SDEM blocks
// (MpSdemCoupling), so the impulse the grid receives is minus the impulse the bodies receive
// (Eqs 17–18).
//
// Bodies are few (boulders in a flow): every particle is tested against each body's bounding
// sphere, without the SDEM coupling's bins. CPU and CUDA solvers, double or float; block sums in
// double, reduced in a fixed order (results do not depend on the thread count). On CUDA the
// contacts run in the SDEM coupling's device backend (its kernel over coupleParticleLevelSets,
// its ordered sums), the grids copied to the device once, the histories kept there.
#pragma once
#include <array>
#include <limits>
#include <memory>
#include <vector>

#include "coupling/CouplingBackend.hpp"
#include "coupling/LevelSetKernelsCommon.hpp"
#include "coupling/MpSdemCoupling.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace coupling {

// A body's signed distance phi on a regular grid in the body's local frame (YADE's
// LevelSet::lsGrid, distField): phi < 0 inside, > 0 outside [m].
struct LevelSetGrid {
  Vec3 min = Vec3::Zero();         // local position of grid point (0, 0, 0) [m]
  double spacing = 0;              // [m], > 0
  std::array<int, 3> nGP = {0, 0, 0};  // grid points per axis, each >= 2
  std::vector<double> dist;        // phi at (i, j, k), index (i nGP[1] + j) nGP[2] + k [m], finite
};

// The coarsest grid spacing a body may have for material points of contact radius R_p0 [m]:
// R_p0. Trilinear interpolation reproduces the distance to a flat face exactly, but
// overestimates it near a convex edge or corner, by up to 0.146 h at the centre of an edge's
// cell and 0.257 h near a corner (phi = |x| sampled at the cell's corners). At h <= R_p0 that
// error stays below a quarter of the barrier's reach R_p0, so a corner pushes back from three
// quarters of the overlap range on; at h = 2 R_p0 points would sink half their radius into
// corners before the barrier saw them.
inline double levelSetSpacingLimit(double particleRadius) { return particleRadius; }

class MpLevelSetCoupling : public CouplingReport {
 public:
  MpLevelSetCoupling() : CouplingReport("LevelSet body index", "a body index") {}
  // Add a body: its YADE id (for messages and the caller's look-ups), its grid and the contact
  // physics of the pair "flow, this body" (checkPairPhys ranges). Returns its index.
  // ParameterError for a grid out of range (names the field).
  int addBody(int externalId, LevelSetGrid grid, const sdem::BarrierPhys& phys);
  int numBodies() const { return static_cast<int>(grids_.size()); }
  int externalId(int i) const { return ids_.at(i); }
  double spacing(int i) const { return grids_.at(i).spacing; }
  const LevelSetGrid& grid(int i) const { return grids_.at(i); }
  // The pose of body i set by the last setState: its grid frame's origin [m] and rotation
  // local -> world.
  Vec3 position(int i) const;
  Mat3 rotation(int i) const;

  // Pose and motion of body i for the next step (world frame): position of the grid frame's
  // origin [m], orientation local -> world, velocity [m/s], angular velocity [rad/s], mass [kg]
  // (> 0 unless fixed), smallest principal moment of inertia [kg m^2], and whether it responds
  // to forces (a fixed body: effective mass of a contact = the particle's).
  void setState(int i, const Vec3& pos, const Quat& ori, const Vec3& vel, const Vec3& angVel, double mass,
                double minInertia, bool fixed);

  // ParameterError naming the first body whose grid spacing exceeds levelSetSpacingLimit of the
  // smallest particle radius R_p0 [m] (the body id, its spacing and R_p0).
  void checkResolution(double particleRadius) const;

  // Tangential-history slots per particle, in [1, 4] (default 2), as MpSdemCoupling's.
  void setHistorySlots(int slots);
  int historySlots() const { return slots_; }

  // ---- checkpoint of the tangential histories, as MpSdemCoupling's: per particle `slots` keys
  // and 3 x slots xi values, elastic tangential forces [N] (a float run's converted to double).
  // setHistories() makes them current for the next step, for a particle set of keys.size() /
  // slots particles. After a step on CUDA they live on the device: pullHistories() brings them
  // to the host before these are read (a no-op otherwise).
  void pullHistories();
  std::vector<long long> historyKeys() const;
  std::vector<double> historyXi() const;
  void setHistories(const std::vector<long long>& keys, const std::vector<double>& xi);

  // One step at the particles of `view` (host or CUDA device memory; they must stay put until
  // the solver's step), of length dt from stepStart [s] (the flow's time, at which the contacts
  // are found: the first contacts): adds their contact forces into view.force and sums the
  // bodies' share.
  // `safety` is the time-step safety of the approach bounds, `watch` [m] how far beyond contact
  // closing pairs are examined (a grid cell). On CUDA the contacts are queued on the device and
  // waited for (the flow's step, queued after, reads their forces). RuntimeFailure when a
  // particle centre reaches a body's surface, or for a device view in a build without CUDA;
  // ParameterError (checkResolution) when a particle set smaller than the grids allow appears.
  void computeForces(const mpm::ParticleView& view, double dt, double stepStart, double safety, double watch);

  // ---- results of the last computeForces, per body index (world frame): force, torque (about
  // the body's position, its grid's origin), contactCount, stiffness sums, step bounds and
  // energies of CouplingReport, and
  long totalContacts() const;
  // The contacts, by particle number (featureKind: sdem::kFeatureFace; block: the body index);
  // those of body `body` only, or all for body < 0.
  std::vector<MpContactRecord> contacts(int body = -1) const;
  // safety x the smallest sqrt(m / sum k) and sqrt(I_min / sum k_r) over the moving bodies of the
  // last step, from their flow contacts alone [s] (+inf without).
  double bodyContactStep(double safety) const;

 private:
  const std::vector<double>& lastSums() const override { return sums_; }
  double stepStart_ = 0;  // the start of computeForces' step [s]
  int reportedBodies() const override { return numBodies(); }
  template <typename T>
  void run(const mpm::ParticleView& view, const BlockState<T>* B, const LevelSetGridView<T>* G,
           const sdem::BarrierCoulombPhys<T>* phys, std::vector<T>& xi, std::vector<MpContact<T>>& contacts,
           double dt, double safety, double watch);
  template <typename T>
  void reduce(const std::vector<MpContact<T>>& contacts, const BlockState<T>* B, double dt);
  void runDevice(const mpm::ParticleView& view, double dt, double safety, double watch);
  // The device's histories become the host's current ones (those a later device step uploads).
  void historiesToHost();
  [[noreturn]] void centreReached(long particle, int body) const;

  std::vector<int> ids_;
  std::vector<LevelSetGrid> grids_;
  std::vector<std::vector<float>> distF_;  // float copies of the grids, for a float solver
  std::vector<sdem::BarrierCoulombPhys<double>> phys_;
  std::vector<BlockState<double>> bodies_;
  std::vector<double> minInertia_;
  std::vector<char> stateSet_;
  int slots_ = 2;
  std::size_t particleCount_ = 0;
  std::vector<long long> key_;
  std::vector<unsigned> written_;
  std::vector<double> xi_;
  std::vector<float> xiF_;
  unsigned historyStep_ = 0;
  std::vector<MpContact<double>> contacts_;
  std::vector<MpContact<float>> contactsF_;
  bool floatRun_ = false;
  std::vector<double> sums_;
  // CUDA: the backend (made at the first device step), the grids as it reads them, whether a
  // body was added since it last read them, whether the last step's contacts are there, whether
  // the current histories are there (the last step that ran anywhere ran there: a step without
  // particles or bodies leaves them where they are) and whether the host's histories
  // (setHistories, or those a CPU step or a replaced backend left) still have to go there
  std::unique_ptr<CouplingDeviceBackend> device_;
  mpm::Precision devicePrecision_ = mpm::Precision::Double;
  std::vector<LevelSetGridView<double>> gridViews_;
  bool gridsChanged_ = true;
  bool onDevice_ = false;
  bool historiesOnDevice_ = false;
  bool historiesToDevice_ = false;
};

}  // namespace coupling
}  // namespace mpmsdem
