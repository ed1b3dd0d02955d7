// Outputs of a coupled run, written alike by mpmsdem.CoupledEngine (YADE) and mpmsdem-run:
//   <dir>/coupled.h5  append-only series (pkg/io/Hdf5Writer): time, step, and per block, in the
//                     order of the root attribute "ids": pos, vel, rotation (rotation vector from
//                     the block's reference orientation), flow_force F_t, face_force F_f,
//                     edge_force F_e (§3.2.3), flow_torque, flow_impulse and flow_angular_impulse
//                     (the flow's force and torque summed over every step times its dt since
//                     the run's start: their difference over an interval between two records
//                     is the mean force and torque between them; NaN in the records before a
//                     restart from a checkpoint that did not keep them, and counted from there)
//                     (each records x 3 blocks),
//                     contacts and flow_first_contact (records x blocks: the start of the first
//                     step whose flow force on the body was not zero [s], CouplingReport::
//                     firstContact; NaN before it, and where not known); energy series are
//                     appended by the caller. Bodies
//                     beside the SDEM blocks (YADE LevelSet bodies, root attribute
//                     "levelset_ids") follow the blocks in "ids" and in every per-block series;
//                     their face_force and edge_force are NaN (a level set has no faces or edges
//                     to tell apart).
//   <dir>/scene.pvd   one ParaView time series: particles (part 0), block surfaces (part 1: the
//                     SDEM blocks' outer surfaces, then the LevelSet bodies' zero level sets,
//                     coupling/LevelSetSurface.hpp; cell data bodyId) and the material
//                     point–body contacts of the last step (part 2: points with the force on the
//                     body, LevelSet bodies' after the blocks'; on CUDA when the coupling records
//                     them) in
//                     vtk/scene_particles_NNNNNN.vtp, vtk/scene_bodies_NNNNNN.vtp and
//                     vtk/scene_contacts_NNNNNN.vtp.
#pragma once
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "coupling/MpLevelSetCoupling.hpp"
#include "coupling/MpSdemCoupling.hpp"
#include "io/Hdf5Writer.hpp"
#include "io/VtkWriter.hpp"
#include "sdem/SdemEngine.hpp"

namespace mpmsdem {
namespace coupling {

// A body beside the SDEM blocks at a record: its state (position: YADE's state.pos) and the
// flow's action on it in the last step and since the run's start (zero before the body's first
// step), and when the flow first touched it (NaN before).
struct OtherBodyRecord {
  Vec3 pos = Vec3::Zero(), vel = Vec3::Zero();
  Quat ori = Quat::Identity();
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  Vec3 impulse = Vec3::Zero(), angularImpulse = Vec3::Zero();
  int contacts = 0;
  double firstContact = std::numeric_limits<double>::quiet_NaN();
};

class CoupledOutput {
 public:
  // Creates dir and dir/vtk; append continues an existing coupled.h5 and scene.pvd. otherIds:
  // the external ids of the bodies recorded after the blocks (LevelSet bodies).
  CoupledOutput(const std::string& dir, bool append, const sdem::SdemEngine& engine,
                const std::vector<int>& otherIds = {});

  // Orientation the "rotation" series is measured from, per block index and then per other body
  // (default: the orientation at a body's first record).
  void setReferenceOrientations(const std::vector<Quat>& ori0) { ori0_ = ori0; }
  const std::vector<Quat>& referenceOrientations() const { return ori0_; }

  // others: one per id of otherIds, in that order.
  void record(double time, long step, const sdem::SdemEngine& engine, const MpSdemCoupling& coupling,
              const std::vector<OtherBodyRecord>& others = {});
  void appendSeries(const std::string& name, double value) { h5_.appendScalar(name, value); }
  // levelSets: the LevelSet bodies coupled beside the blocks, at the poses of their last
  // setState (none: nullptr).
  void writeVtk(double time, mpm::ParticleSlices& particles, const sdem::SdemEngine& engine,
                const MpSdemCoupling& coupling, const MpLevelSetCoupling* levelSets = nullptr);
  io::Hdf5Writer& h5() { return h5_; }
  // A restart from time t [s]: drop the records and ParaView entries written after t by the
  // run that went on past its checkpoint.
  void dropAfter(double t);

 private:
  std::string dir_;
  io::Hdf5Writer h5_;
  io::PvdCollection pvd_;
  std::vector<Quat> ori0_;
  std::size_t others_ = 0;
  std::vector<io::RigidSurface> levelSetLocal_;  // each LevelSet body's surface in its own frame
};

// Outer surfaces of the SDEM bodies at their current poses (ids: the bodies' external ids).
std::vector<io::RigidSurface> bodySurfaces(const sdem::SdemEngine& engine);

}  // namespace coupling
}  // namespace mpmsdem
