// The SDEM engine's YADE bridge (C++ side of mpmsdem.SdemEngine), shared by its binding
// (PySdem.cpp) and the coupled engine's (PyCoupling.cpp).
//
// The bridge exchanges body state and forces with YADE from C++: per step it reads
// pos/ori/vel/angVel of the registered bodies through cached State objects, runs
// SdemEngine::computeForces, and adds forces/torques with O.forces.addF/addT. Bodies added
// as fixed are read once and never again. Any other body whose six DOFs are blocked (YADE
// `dynamic == False`, e.g. blockedDOFs "xyzXYZ") counts as fixed in the engine, so that its
// pairs with fixed bodies skip the narrow phase; it is still read every step, since it may
// move kinematically or be released (readStates says when YADE is asked). The time spent in
// the three phases (read, compute, write) is accumulated so benchmarks can report the
// bridge's share of each step.
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <sstream>

#include "PyConvert.hpp"
#include "coupling/CoupledOutput.hpp"
#include "io/Hdf5Writer.hpp"
#include "io/VtkWriter.hpp"
#include "sdem/SdemEngine.hpp"
#include "sdem/SdemEngine.hpp"

namespace mpmsdem {
namespace py {

using sdem::SdemEngine;
using sdem::SdemMaterial;

using Clock = std::chrono::steady_clock;
inline double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

inline const char* featureName(sdem::FeatureKind k) {
  switch (k) {
    case sdem::FeatureKind::Vertex: return "vertex";
    case sdem::FeatureKind::Edge: return "edge";
    case sdem::FeatureKind::Face: return "face";
  }
  return "?";
}

class YadeSdemBridge {
 public:
  int addMaterial(const SdemMaterial& m) { return engine_.addMaterial(m); }
  // The terrain under the blocks: heights i-major (nx * ny), node (i, j) at (x0 + i s, y0 + j s).
  void setTerrain(const bp::object& heights, int nx, int ny, double x0, double y0, double spacing, int material) {
    mpmsdem::TerrainSpec t;
    t.nx = nx;
    t.ny = ny;
    t.x0 = x0;
    t.y0 = y0;
    t.spacing = spacing;
    const long n = bp::len(heights);
    t.heights.reserve(n);
    for (long k = 0; k < n; ++k) t.heights.push_back(bp::extract<double>(heights[k]));
    engine_.setTerrain(t, material);
  }

  int addBody(std::shared_ptr<sdem::SpheroPolyhedron> shape, int material, double mass, const bp::object& inertia,
              int yadeId, bool fixed) {
    const int i = engine_.addBody(shape, material, mass, toVec3(inertia, "inertia"), yadeId);
    engine_.setFixed(i, fixed);
    addedFixed_.push_back(fixed);
    bodies_.push_back(bp::object());
    states_.push_back(bp::object());
    readOnce_.push_back(0);
    return i;
  }

  // Forget the cached YADE Body and State objects (call after O.bodies was rebuilt or O.load()).
  void refresh() {
    for (auto& b : bodies_) b = bp::object();
    for (auto& s : states_) s = bp::object();
    std::fill(readOnce_.begin(), readOnce_.end(), 0);
  }

  // One step inside YADE's loop: bodies = O.bodies, forces = O.forces, dt = O.dt.
  // The state read here is kept as the last good one only once its forces were computed
  // without error: a failed step can then roll the bodies back (rollBack()).
  void step(const bp::object& bodies, const bp::object& forces, double dt) {
    readStates(bodies);
    keepState(pending_);
    computeForces(dt);
    std::swap(good_, pending_);
    writeForces(forces, nullptr, nullptr);
    ++steps_;
  }

  // After a failed step: put the SDEM bodies (YADE states and this engine) and the contact
  // histories back to the state at the start of the last step that completed. The blow-up
  // guard fires on a state NewtonIntegrator produced from the previous step's forces, so the
  // state YADE holds then is already bad; the one before it is the newest that stepped
  // without error. Returns the YADE iteration that state started, or -1 when no step
  // completed yet (nothing changed).
  long rollBack(const bp::object& bodies) {
    if (!good_.valid) return -1;
    const int n = engine_.numBodies();
    for (int i = 0; i < n; ++i) {
      if (addedFixed_[i]) continue;
      bp::object st = bodies[engine_.externalId(i)].attr("state");
      st.attr("pos") = good_.pos[i];
      st.attr("ori") = good_.ori[i];
      st.attr("vel") = good_.vel[i];
      st.attr("angVel") = good_.angVel[i];
      engine_.setState(i, good_.pos[i], good_.ori[i], good_.vel[i], good_.angVel[i]);
    }
    engine_.setContactHistories(good_.histories);
    frictionOffset_ = good_.friction - engine_.frictionDissipation();
    dampingOffset_ = good_.damping - engine_.dampingDissipation();
    return good_.iter;
  }
  // YADE iteration and time at which the kept good state started (set from Python, which
  // knows O.iter and O.time; -1 / NaN before the first completed step).
  void setStepClock(long iter, double time) {
    pending_.iter = iter;
    pending_.time = time;
  }
  double goodTime() const { return good_.valid ? good_.time : std::nan(""); }

  // The three stages of step(), also composed by the coupled engine.
  // Body states from YADE (bodies added as fixed are read once).
  void readStates(const bp::object& bodies) {
    const auto t0 = Clock::now();
    const int n = engine_.numBodies();
    if (static_cast<int>(states_.size()) != n) throw RuntimeFailure("SDEM bridge: body list out of sync");
    for (int i = 0; i < n; ++i) {
      if (addedFixed_[i] && readOnce_[i]) continue;
      if (states_[i].is_none()) {
        bodies_[i] = bodies[engine_.externalId(i)];
        states_[i] = bodies_[i].attr("state");
      }
      const bp::object& st = states_[i];
      const Vec3 pos = bp::extract<Vec3>(st.attr("pos"));
      const Quat ori = bp::extract<Quat>(st.attr("ori"));
      const Vec3 vel = bp::extract<Vec3>(st.attr("vel"));
      const Vec3 angVel = bp::extract<Vec3>(st.attr("angVel"));
      // Whether YADE can move the body is asked at its first read, while it counts as fixed
      // (to see its release) and while it is at rest (`dynamic = False` stops a body), not
      // of every moving body every step: attribute reads are most of the bridge's cost. A
      // body whose DOFs are blocked while it moves (YADE keeps its velocity) stays a moving
      // one: its contacts are all computed, nothing is saved.
      const bool atRest = vel == Vec3::Zero() && angVel == Vec3::Zero();
      if (!addedFixed_[i] && (!readOnce_[i] || atRest || engine_.isFixed(i)))
        engine_.setFixed(i, !bp::extract<bool>(bodies_[i].attr("dynamic")));
      checkState(i, pos, ori, vel, angVel);
      engine_.setState(i, pos, ori, vel, angVel);
      readOnce_[i] = 1;
    }
    readSeconds_ += seconds(t0, Clock::now());
  }
  void computeForces(double dt) {
    const auto t0 = Clock::now();
    engine_.computeForces(dt);
    computeSeconds_ += seconds(t0, Clock::now());
  }
  // Contact forces (plus extra per-body forces and torques, e.g. from the flow) to O.forces.
  void writeForces(const bp::object& forces, const std::vector<Vec3>* extraF, const std::vector<Vec3>* extraT) {
    const auto t0 = Clock::now();
    const int n = engine_.numBodies();
    bp::object addF = forces.attr("addF"), addT = forces.attr("addT");
    for (int i = 0; i < n; ++i) {
      const Vec3 f = engine_.force(i) + (extraF ? (*extraF)[i] : Vec3::Zero());
      const Vec3 t = engine_.torque(i) + (extraT ? (*extraT)[i] : Vec3::Zero());
      if (f.squaredNorm() == 0 && t.squaredNorm() == 0) continue;
      addF(engine_.externalId(i), f);
      if (!addedFixed_[i]) addT(engine_.externalId(i), t);
    }
    writeSeconds_ += seconds(t0, Clock::now());
  }
  sdem::SdemEngine& engine() { return engine_; }
  void countStep() { ++steps_; }

  // Blow-up guard: a body whose state is not finite or moves faster than maxSpeed stops the run.
  void checkState(int i, const Vec3& pos, const Quat& ori, const Vec3& vel, const Vec3& angVel) const {
    const bool finite = pos.allFinite() && ori.coeffs().allFinite() && vel.allFinite() && angVel.allFinite();
    if (finite && vel.norm() <= maxSpeed_) return;
    std::ostringstream os;
    os << "body " << engine_.externalId(i) << (finite ? " moves at " : " has a non-finite state: ") << "|vel| = "
       << vel.norm() << " m/s (maxSpeed = " << maxSpeed_ << " m/s), pos = (" << pos.transpose()
       << ") m: the run blew up (time step too large for the contact stiffness?)";
    throw RuntimeFailure(os.str());
  }
  double maxSpeed() const { return maxSpeed_; }
  void setMaxSpeed(double v) {
    if (!(v > 0)) throwParameter("maxSpeed", v, "m/s", "> 0");
    maxSpeed_ = v;
  }

  bp::dict timings() const {
    bp::dict d;
    d["steps"] = steps_;
    d["read"] = readSeconds_;
    d["compute"] = computeSeconds_;
    d["write"] = writeSeconds_;
    return d;
  }
  void resetTimings() {
    steps_ = 0;
    readSeconds_ = computeSeconds_ = writeSeconds_ = 0;
  }

  // Contacts of the last step as numpy arrays (one row per contact point).
  bp::dict contacts() const {
    const auto& rec = engine_.contacts();
    const npy_intp n = static_cast<npy_intp>(rec.size());
    std::vector<double> point(3 * n), normal(3 * n), ft(3 * n), fn(n), overlap(n), kn(n);
    std::vector<long> idA(n), idB(n), sliding(n);
    bp::list kindA, kindB;
    for (npy_intp c = 0; c < n; ++c) {
      const auto& r = rec[c];
      for (int k = 0; k < 3; ++k) {
        point[3 * c + k] = r.point[k];
        normal[3 * c + k] = r.normal[k];
        ft[3 * c + k] = r.tangentialForce[k];
      }
      fn[c] = r.normalForce;
      overlap[c] = r.overlap;
      kn[c] = r.normalStiffness;
      idA[c] = r.externalA;
      idB[c] = r.externalB;
      sliding[c] = r.sliding ? 1 : 0;
      kindA.append(featureName(r.key.kindA));
      kindB.append(featureName(r.key.kindB));
    }
    bp::dict d;
    d["id1"] = numpyArrayInt(idA);
    d["id2"] = numpyArrayInt(idB);
    d["point"] = numpyArray(point.data(), n, 3);
    d["normal"] = numpyArray(normal.data(), n, 3);
    d["normalForce"] = numpyArray(fn.data(), n, 0);
    d["tangentialForce"] = numpyArray(ft.data(), n, 3);
    d["overlap"] = numpyArray(overlap.data(), n, 0);
    d["normalStiffness"] = numpyArray(kn.data(), n, 0);
    d["sliding"] = numpyArrayInt(sliding);
    d["feature1"] = kindA;
    d["feature2"] = kindB;
    return d;
  }

  // Contact histories for checkpoints: list of (idA, idB, kindA, kindB, indexA, indexB, xi).
  bp::list histories() const {
    bp::list l;
    for (const auto& h : engine_.contactHistories())
      l.append(bp::make_tuple(h.key.bodyA, h.key.bodyB, static_cast<int>(h.key.kindA), static_cast<int>(h.key.kindB),
                              h.key.indexA, h.key.indexB, h.xi));
    return l;
  }
  void setHistories(const bp::list& l) {
    std::vector<sdem::ContactHistoryEntry> h;
    const long n = bp::len(l);
    for (long i = 0; i < n; ++i) {
      bp::object t = l[i];
      sdem::ContactHistoryEntry e;
      e.key.bodyA = bp::extract<int>(t[0]);
      e.key.bodyB = bp::extract<int>(t[1]);
      e.key.kindA = static_cast<sdem::FeatureKind>(static_cast<int>(bp::extract<int>(t[2])));
      e.key.kindB = static_cast<sdem::FeatureKind>(static_cast<int>(bp::extract<int>(t[3])));
      e.key.indexA = bp::extract<int>(t[4]);
      e.key.indexB = bp::extract<int>(t[5]);
      e.xi = toVec3(t[6], "xi");
      h.push_back(e);
    }
    engine_.setContactHistories(h);
  }

  // ---- outputs: <dir>/sdem.h5 (append-only series) and <dir>/bodies.pvd + vtk/bodies_*.vtp
  // A checkpoint is being taken: what a restart from it goes back to (Hdf5Writer::commit).
  void commitOutput() {
    if (h5_) h5_->commit();
  }
  // append: continue the files of a restored run; records after `time` (the checkpoint's),
  // left by the run that went on past it, are dropped. Returns the times of the last HDF5
  // record and the last VTK entry kept (NaN: none), from which the next ones are due.
  bp::tuple openOutput(const std::string& dir, bool append, double time) {
    namespace fs = std::filesystem;
    fs::create_directories(fs::path(dir) / "vtk");
    const std::string h5 = (fs::path(dir) / "sdem.h5").string();
    if (append) io::resumeFromCommit(h5);  // the file as of the checkpoint: a kill may have damaged it since
    h5_ = std::make_unique<io::Hdf5Writer>(h5, append ? io::Hdf5Writer::Mode::Append : io::Hdf5Writer::Mode::Truncate);
    double lastRecord = std::nan(""), lastVtk = std::nan("");
    if (append) h5_->truncateSeriesAfter("time", time, &lastRecord);
    std::ostringstream ids;
    ids << "[";
    for (int i = 0; i < engine_.numBodies(); ++i) ids << (i ? ", " : "") << engine_.externalId(i);
    ids << "]";
    h5_->setAttribute("ids", ids.str());
    h5_->setAttribute("units", "SI: m, s, N, N m; ori as quaternion w x y z; per-body series are (records, 3 x bodies) "
                               "in the order of the attribute ids");
    pvd_ = std::make_unique<io::PvdCollection>((fs::path(dir) / "bodies.pvd").string(), append);
    if (append) lastVtk = pvd_->dropAfter(time);
    dir_ = dir;
    return bp::make_tuple(lastRecord, lastVtk);
  }
  // One record of the state of the last step: time, step, per body pos, ori, vel, angVel,
  // force, torque, and the number of contact points.
  void record(double time, long step) { recordOf(engine_, time, step); }
  // A record of the state YADE holds now, after the last step moved the bodies: the forces
  // are those the next step would compute, taken on a copy of the engine so that the contact
  // histories and dissipations the run continues from are untouched.
  void recordCurrent(const bp::object& bodies, double time, long step, double dt) {
    requireOutput();
    readStates(bodies);
    SdemEngine probe = engine_;
    probe.computeForces(dt);
    recordOf(probe, time, step);
  }
  void recordOf(const SdemEngine& e, double time, long step) {
    requireOutput();
    const int n = e.numBodies();
    std::vector<double> pos(3 * n), ori(4 * n), vel(3 * n), angVel(3 * n), f(3 * n), t(3 * n);
    for (int i = 0; i < n; ++i) {
      const Quat& q = e.orientation(i);
      const double qc[4] = {q.w(), q.x(), q.y(), q.z()};
      for (int k = 0; k < 4; ++k) ori[4 * i + k] = qc[k];
      for (int k = 0; k < 3; ++k) {
        pos[3 * i + k] = e.position(i)[k];
        vel[3 * i + k] = e.velocity(i)[k];
        angVel[3 * i + k] = e.angularVelocity(i)[k];
        f[3 * i + k] = e.force(i)[k];
        t[3 * i + k] = e.torque(i)[k];
      }
    }
    h5_->appendScalar("time", time);
    h5_->appendScalar("step", static_cast<double>(step));
    h5_->appendVector("pos", pos);
    h5_->appendVector("ori", ori);
    h5_->appendVector("vel", vel);
    h5_->appendVector("angVel", angVel);
    h5_->appendVector("force", f);
    h5_->appendVector("torque", t);
    h5_->appendScalar("contacts", static_cast<double>(e.contacts().size()));
  }
  // The outer shapes of all bodies at their current pose, for ParaView.
  void writeVtk(double time) {
    requireOutput();
    std::ostringstream name;
    name << "vtk/bodies_" << std::setw(6) << std::setfill('0') << pvd_->size() << ".vtp";
    writeBodiesVtp((std::filesystem::path(dir_) / name.str()).string());
    pvd_->add(time, name.str());
  }
  void writeBodiesVtp(const std::string& path) const { io::writeRigidSurfacesVtp(path, coupling::bodySurfaces(engine_)); }

  Vec3 force(int i) const { return engine_.force(i); }
  Vec3 torque(int i) const { return engine_.torque(i); }
  void requireOutput() const {
    if (!h5_) throw ParameterError("output: call openOutput(dir) before writing outputs");
  }
  int numBodies() const { return engine_.numBodies(); }
  int yadeId(int i) const { return engine_.externalId(i); }
  double criticalTimeStep() const { return engine_.criticalTimeStep(); }
  // sdem::autoTimeStep from the critical step of the last step's contacts (or `critical` when
  // smaller: a restored run's) and the approach step of the bodies' velocities, read from YADE
  // first (a restored run must see the state it continues).
  double autoStep(const bp::object& bodies, double factor, double critical, double lastDt) {
    readStates(bodies);
    return sdem::autoTimeStep(factor, std::min(critical, engine_.criticalTimeStep()), engine_.approachTimeStep(),
                              lastDt);
  }
  // The step check allows dt up to this factor times the critical step (2 under dtAuto).
  double checkFactor() const { return engine_.timeStepCheckFactor(); }
  void setCheckFactor(double f) { engine_.setTimeStepCheckFactor(f); }
  double timeStepSafety() const { return engine_.timeStepSafety(); }
  void setTimeStepSafety(double c) { engine_.setTimeStepSafety(c); }
  bool strict() const { return engine_.strictTimeStep(); }
  void setStrict(bool s) { engine_.setStrictTimeStep(s); }
  long warnings() const { return engine_.timeStepWarnings(); }
  double barrierEnergy() const { return engine_.barrierEnergy(); }
  double tangentialEnergy() const { return engine_.tangentialEnergy(); }
  // Cumulative dissipations continue across a restore (setDissipation) and a roll-back: the
  // engine's own counters start at 0, the offsets carry what came before.
  double frictionDissipation() const { return engine_.frictionDissipation() + frictionOffset_; }
  double dampingDissipation() const { return engine_.dampingDissipation() + dampingOffset_; }
  void setDissipation(double friction, double damping) {
    frictionOffset_ = friction - engine_.frictionDissipation();
    dampingOffset_ = damping - engine_.dampingDissipation();
  }
  int numContacts() const { return static_cast<int>(engine_.contacts().size()); }
  long narrowPhasePairs() const { return engine_.narrowPhasePairs(); }

 private:
  struct KeptState {
    std::vector<Vec3> pos, vel, angVel;
    std::vector<Quat> ori;
    std::vector<sdem::ContactHistoryEntry> histories;
    double friction = 0, damping = 0, time = std::nan("");
    long iter = -1;
    bool valid = false;
  };
  void keepState(KeptState& k) const {
    const int n = engine_.numBodies();
    k.pos.resize(n);
    k.ori.resize(n);
    k.vel.resize(n);
    k.angVel.resize(n);
    for (int i = 0; i < n; ++i) {
      k.pos[i] = engine_.position(i);
      k.ori[i] = engine_.orientation(i);
      k.vel[i] = engine_.velocity(i);
      k.angVel[i] = engine_.angularVelocity(i);
    }
    k.histories = engine_.contactHistories();
    k.friction = frictionDissipation();
    k.damping = dampingDissipation();
    k.valid = true;
  }

  SdemEngine engine_;
  KeptState good_, pending_;
  double frictionOffset_ = 0, dampingOffset_ = 0;
  std::vector<char> addedFixed_;  // added with fixed = true: read once, never rolled back
  std::vector<bp::object> bodies_, states_;
  std::vector<char> readOnce_;
  std::unique_ptr<io::Hdf5Writer> h5_;
  std::unique_ptr<io::PvdCollection> pvd_;
  std::string dir_;
  double maxSpeed_ = 1e3;
  long steps_ = 0;
  double readSeconds_ = 0, computeSeconds_ = 0, writeSeconds_ = 0;
};

}  // namespace py
}  // namespace mpmsdem
