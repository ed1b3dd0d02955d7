// Binding of the MP–SDEM coupling inside YADE (C++ side of mpmsdem.CoupledEngine). One call
// per YADE step is the driver's coupled step (coupling::coupledStep, paper §2.3): block states
// from YADE -> MP–block contacts (particle forces into the MPM force buffer, block shares) ->
// block–block contacts and the block forces (contacts + flow) to O.forces, while a device runs
// the MPM step -> the MPM step's end; YADE's NewtonIntegrator then moves the blocks.
// Particle data stays in the solver's memory (on the GPU for the CUDA backend).
#include <cstring>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <limits>
#include <sstream>

#include "PyMpm.hpp"
#include "PySdem.hpp"
#include "coupling/CoupledOutput.hpp"
#include "coupling/CoupledScene.hpp"
#include "mpm/MpmKernelsCommon.hpp"
#include "coupling/CoupledWorld.hpp"
#include "coupling/MpLevelSetCoupling.hpp"
#include "coupling/MpSdemCoupling.hpp"

namespace mpmsdem {
namespace py {

namespace {

class PyCoupling {
 public:
  PyCoupling(YadeSdemBridge& sdem, PyMpm& mpm) : sdem_(sdem), mpm_(mpm), coupling_(sdem.engine()) {}

  void setPair(int material, double kc, double friction, double poisson, double normalDamping,
               double tangentialDamping) {
    sdem::BarrierPhys p;
    p.barrierStiffness = kc;
    p.friction = friction;
    p.poisson = poisson;
    p.normalDamping = normalDamping;
    p.tangentialDamping = tangentialDamping;
    coupling_.setPair(material, p);
  }
  int historySlots() const { return coupling_.historySlots(); }
  bool recordContacts() const { return coupling_.recordContacts(); }
  void setRecordContacts(bool on) { coupling_.setRecordContacts(on); }
  void setHistorySlots(int s) {
    coupling_.setHistorySlots(s);
    levelSets_.setHistorySlots(s);
  }

  // A YADE LevelSet body (id) coupled with the flow: its grid (local frame: min [m], spacing [m],
  // grid points per axis, phi as float64 bytes in distField[i][j][k] order) and the pair's
  // contact physics. ValueError for a bad grid or physics, or a grid coarser than the flow's
  // points allow (MpLevelSetCoupling::checkResolution).
  void addLevelSet(int id, const Vec3& min, double spacing, int nx, int ny, int nz, const bp::object& dist,
                   double kc, double friction, double poisson, double normalDamping, double tangentialDamping) {
    coupling::LevelSetGrid g;
    g.min = min;
    g.spacing = spacing;
    g.nGP = {nx, ny, nz};
    char* p = nullptr;
    Py_ssize_t n = 0;
    if (PyBytes_AsStringAndSize(dist.ptr(), &p, &n) < 0) bp::throw_error_already_set();
    if (n % sizeof(double)) throw ParameterError("LevelSet distField: byte length is not a whole float64 array");
    g.dist.resize(n / sizeof(double));
    if (n) std::memcpy(g.dist.data(), p, n);
    sdem::BarrierPhys phys;
    phys.barrierStiffness = kc;
    phys.friction = friction;
    phys.poisson = poisson;
    phys.normalDamping = normalDamping;
    phys.tangentialDamping = tangentialDamping;
    levelSets_.addBody(id, std::move(g), phys);
    lsStates_.push_back(bp::object());
    lsBodies_.push_back(bp::object());
    if (mpm_.solver().numParticles() > 0) {
      mpm::ParticleSet all;
      mpm_.solver().getParticles(all);
      double v0 = std::numeric_limits<double>::infinity();
      for (double v : all.volume0) v0 = std::min(v0, v);
      levelSets_.checkResolution(std::cbrt(3 * v0 / (4 * 3.14159265358979323846)));
    }
  }
  int numLevelSets() const { return levelSets_.numBodies(); }

  void step(const bp::object& bodies, const bp::object& forces, double dt) {
    sdem_.readStates(bodies);
    readLevelSets(bodies);
    const bool levelSets = levelSets_.numBodies() > 0;
    coupling::coupledStep(
        mpm_.solver(), coupling_, dt,
        [&] {
          sdem_.computeForces(dt);
          coupling_.blockForces(force_, torque_);
          sdem_.writeForces(forces, &force_, &torque_);
          sdem_.countStep();
          if (levelSets) levelSetForces(forces);
        },
        stages_, levelSets ? std::function<void()>([&] { runLevelSetContacts(dt); }) : std::function<void()>());
    restoredApproach_ = std::numeric_limits<double>::quiet_NaN();
    ++steps_;
    const double limit = contactStep();
    if (dt > checkFactor_ * limit) {
      if (strict_) {
        std::ostringstream os;
        os << "dt = " << dt << " s: must be <= ";
        if (checkFactor_ != 1) os << checkFactor_ << " x ";
        os << "the coupled contact critical step " << limit
           << " s (MP-block and block-block contacts: sqrt(m / k) with the tangent barrier stiffness)";
        throw RuntimeFailure(os.str());
      }
      ++warnings_;
    }
  }

  // The SDEM part (coupledContactStep) and the LevelSet bodies' flow contacts, with the same
  // safety factor.
  double contactStep() const {
    const double safety = sdem_.engine().timeStepSafety();
    return std::min({coupling::coupledContactStep(sdem_.engine(), coupling_),
                     safety * levelSets_.particleCriticalStep(), levelSets_.bodyContactStep(safety)});
  }
  double criticalTimeStep() { return std::min(mpm_.solver().stableTimeStep(), contactStep()); }

  // A block of the SDEM engine that no coupling step has seen yet (before the first step, the
  // initial record) has had no flow force.
  Vec3 force(int i) const { return seen(i) ? coupling_.force(i) : Vec3::Zero(); }
  Vec3 torque(int i) const { return seen(i) ? coupling_.torque(i) : Vec3::Zero(); }
  Vec3 faceForce(int i) const { return seen(i) ? coupling_.faceForce(i) : Vec3::Zero(); }
  Vec3 edgeForce(int i) const { return seen(i) ? coupling_.edgeForce(i) : Vec3::Zero(); }
  int contactCount(int i) const { return seen(i) ? coupling_.contactCount(i) : 0; }
  Vec3 impulse(int i) const { return seen(i) ? coupling_.impulse(i) : Vec3::Zero(); }
  Vec3 angularImpulse(int i) const { return seen(i) ? coupling_.angularImpulse(i) : Vec3::Zero(); }
  double firstContact(int i) const {
    return seen(i) ? coupling_.firstContact(i) : std::numeric_limits<double>::quiet_NaN();
  }
  long totalContacts() const { return coupling_.totalContacts() + levelSets_.totalContacts(); }
  long historyOverflow() const { return coupling_.historyOverflow() + levelSets_.historyOverflow(); }

  // ---- LevelSet bodies, by their index in the order added (results of the last step)
  Vec3 levelSetForce(int i) const { return levelSets_.force(i); }
  Vec3 levelSetTorque(int i) const { return levelSets_.torque(i); }
  int levelSetContactCount(int i) const { return levelSets_.contactCount(i); }
  Vec3 levelSetImpulse(int i) const { return levelSets_.impulse(i); }
  Vec3 levelSetAngularImpulse(int i) const { return levelSets_.angularImpulse(i); }
  double levelSetFirstContact(int i) const { return levelSets_.firstContact(i); }
  bp::dict levelSetContacts(int only) const {
    const std::vector<coupling::MpContactRecord> rec = levelSets_.contacts(only);
    return contactArrays(rec, [this](int b) { return levelSets_.externalId(b); }, false);
  }

  // The last step's MP–block contacts as numpy arrays, one row per contact (CPU backends):
  // those of SDEM body index `only`, or all of them for only < 0.
  bp::dict contacts(int only) const {
    const std::vector<coupling::MpContactRecord> rec = coupling_.contacts(only);
    return contactArrays(rec, [this](int b) { return sdem_.engine().externalId(b); }, true);
  }

  // Contact records as numpy arrays, block ids through yadeId; `features`: a block's core
  // feature per row (a LevelSet body has none).
  template <typename Id>
  static bp::dict contactArrays(const std::vector<coupling::MpContactRecord>& rec, const Id& yadeId,
                                bool features) {
    const npy_intp n = static_cast<npy_intp>(rec.size());
    std::vector<double> point(3 * n), normal(3 * n), force(3 * n), fn(n), overlap(n);
    std::vector<long> particle(n), block(n);
    bp::list feature;
    for (npy_intp c = 0; c < n; ++c) {
      const coupling::MpContactRecord& r = rec[c];
      for (int k = 0; k < 3; ++k) {
        point[3 * c + k] = r.point[k];
        normal[3 * c + k] = r.normal[k];
        force[3 * c + k] = r.force[k];
      }
      fn[c] = r.normalForce;
      overlap[c] = r.overlap;
      particle[c] = r.particle;
      block[c] = yadeId(r.block);
      if (features) feature.append(featureName(static_cast<sdem::FeatureKind>(r.featureKind)));
    }
    bp::dict d;
    d["particle"] = numpyArrayInt(particle);
    d["block"] = numpyArrayInt(block);
    d["point"] = numpyArray(point.data(), n, 3);
    d["normal"] = numpyArray(normal.data(), n, 3);
    d["force"] = numpyArray(force.data(), n, 3);
    d["normalForce"] = numpyArray(fn.data(), n, 0);
    d["overlap"] = numpyArray(overlap.data(), n, 0);
    if (features) d["feature"] = feature;
    return d;
  }

  bp::dict energies() const {
    bp::dict d;
    d["barrier"] = coupling_.barrierEnergy() + levelSets_.barrierEnergy();
    d["tangential"] = coupling_.springEnergy() + levelSets_.springEnergy();
    d["friction"] = coupling_.frictionDissipation() + levelSets_.frictionDissipation();
    d["damping"] = coupling_.dampingDissipation() + levelSets_.dampingDissipation();
    return d;
  }
  bp::dict timings() const {
    bp::dict d;
    d["steps"] = steps_;
    d["coupling"] = stages_.coupling;
    d["mpm"] = stages_.mpm;
    return d;
  }
  void resetTimings() {
    steps_ = 0;
    stages_ = {};
  }

  // ---- outputs: <dir>/coupled.h5 and <dir>/scene.pvd (coupling::CoupledOutput, the layout the
  // driver writes too)
  void openOutput(const std::string& dir, bool append) {
    std::vector<int> levelSetIds;
    for (int i = 0; i < levelSets_.numBodies(); ++i) levelSetIds.push_back(levelSets_.externalId(i));
    output_ = std::make_unique<coupling::CoupledOutput>(dir, append, sdem_.engine(), levelSetIds);
    if (!ori0_.empty()) output_->setReferenceOrientations(ori0_);
  }
  // ParameterError (ValueError) naming the first block (YADE id) faster than maxSpeed [m/s].
  void checkBlockSpeeds(const bp::object& bodies, double maxSpeed) {
    sdem_.readStates(bodies);
    const sdem::SdemEngine& e = sdem_.engine();
    for (int i = 0; i < e.numBodies(); ++i)
      coupling::checkBlockSpeed(e, i, maxSpeed, "body " + std::to_string(e.externalId(i)), "maxBlockSpeed");
  }
  // Ten times the flow's P-wave speed [m/s]: the default block speed limit (run.max_block_speed).
  double defaultMaxBlockSpeed() const { return 10 * mpm::pWaveSpeed(mpm_.solver().params().material); }
  // One warning per block (YADE id) whose rounded body lies wholly outside the MPM grid (it can
  // never touch the flow), from the states in `bodies`; also the output's "warnings" attribute.
  bp::list outsideGridWarnings(const bp::object& bodies) {
    sdem_.readStates(bodies);
    const sdem::SdemEngine& e = sdem_.engine();
    bp::list out;
    std::string all;
    for (int i = 0; i < e.numBodies(); ++i) {
      if (!(coupling::distanceFromGrid(e, i, mpm_.solver().params()) > 0)) continue;
      const std::string w = "body " + std::to_string(e.externalId(i)) + " " +
                            coupling::outsideGridMessage(e, i, mpm_.solver().params());
      out.append(w);
      all += (all.empty() ? "" : "\n") + w;
    }
    if (output_ && !all.empty()) output_->h5().setAttribute("warnings", all);
    return out;
  }
  // A checkpoint is being taken: what a restart from it goes back to (Hdf5Writer::commit).
  void commitOutput() {
    if (output_) output_->h5().commit();
  }
  // The blocks' state is read from YADE first: between two steps NewtonIntegrator has moved
  // them past what the engine last read.
  void record(const bp::object& bodies, double time, long step) {
    requireOutput();
    sdem_.readStates(bodies);
    output_->record(time, step, sdem_.engine(), coupling_, levelSetRecords(bodies));
  }
  void appendSeries(const std::string& name, double value) {
    requireOutput();
    output_->appendSeries(name, value);
  }
  void writeVtk(const bp::object& bodies, double time) {
    requireOutput();
    sdem_.readStates(bodies);
    readLevelSets(bodies);
    output_->writeVtk(time, mpm_.outputParticles(), sdem_.engine(), coupling_,
                      levelSets_.numBodies() > 0 ? &levelSets_ : nullptr);
  }

  // ---- checkpoint: tangential histories as raw bytes (int64 keys, float64 xi; the restart
  // is bit-for-bit), the cumulative dissipations, and each block's orientation at the first
  // record (the origin of the `rotation` series).
  bp::tuple histories() {
    coupling_.pullHistories();
    return historyBytes(coupling_);
  }
  void setHistories(const bp::object& keys, const bp::object& xi) { setHistoryBytes(coupling_, keys, xi); }
  bp::tuple blockDissipation() const {
    return bp::make_tuple(coupling_.frictionDissipation(), coupling_.dampingDissipation());
  }
  void setDissipation(double friction, double damping) { coupling_.setDissipation(friction, damping); }
  // The same for the LevelSet bodies' contacts (their dissipations kept apart, so that a restart
  // adds up the same numbers as the unbroken run).
  bp::tuple levelSetHistories() {
    levelSets_.pullHistories();
    return historyBytes(levelSets_);
  }
  void setLevelSetHistories(const bp::object& keys, const bp::object& xi) { setHistoryBytes(levelSets_, keys, xi); }
  bp::tuple levelSetDissipation() const {
    return bp::make_tuple(levelSets_.frictionDissipation(), levelSets_.dampingDissipation());
  }
  void setLevelSetDissipation(double friction, double damping) { levelSets_.setDissipation(friction, damping); }
  // The flow's impulses on the blocks and on the LevelSet bodies since the run's start
  // (CouplingReport::impulses, 6 a body), which coupled.h5's flow_impulse series go on from.
  bp::list blockImpulses() const { return doubleList(coupling_.impulses()); }
  void setImpulses(const bp::object& values) { coupling_.setImpulses(sequenceOfDoubles(values)); }
  bp::list levelSetImpulses() const { return doubleList(levelSets_.impulses()); }
  void setLevelSetImpulses(const bp::object& values) { levelSets_.setImpulses(sequenceOfDoubles(values)); }
  // When the flow first touched each block and LevelSet body (CouplingReport::firstContacts:
  // NaN not yet, -inf not kept), and back after the impulses (CouplingReport::
  // restoreFirstContacts; impulsesKept: whether the checkpoint kept the impulses).
  bp::list blockFirstContacts() const { return doubleList(coupling_.firstContacts()); }
  void setFirstContacts(const bp::object& values, bool impulsesKept) {
    coupling_.restoreFirstContacts(sequenceOfDoubles(values), impulsesKept, sdem_.engine().numBodies());
  }
  bp::list levelSetFirstContacts() const { return doubleList(levelSets_.firstContacts()); }
  void setLevelSetFirstContacts(const bp::object& values, bool impulsesKept) {
    levelSets_.restoreFirstContacts(sequenceOfDoubles(values), impulsesKept, levelSets_.numBodies());
  }
  bp::list referenceOrientations() const {
    bp::list l;
    for (const Quat& q : output_ ? output_->referenceOrientations() : ori0_)
      l.append(bp::make_tuple(q.w(), q.x(), q.y(), q.z()));
    return l;
  }
  void setReferenceOrientations(const bp::list& l) {
    ori0_.clear();
    for (long i = 0; i < bp::len(l); ++i) {
      bp::object q = l[i];
      ori0_.push_back(Quat(bp::extract<double>(q[0]), bp::extract<double>(q[1]), bp::extract<double>(q[2]),
                           bp::extract<double>(q[3])));
    }
    if (output_) output_->setReferenceOrientations(ori0_);
  }

  bool strict() const { return strict_; }
  void setStrict(bool s) { strict_ = s; }
  long warnings() const { return warnings_; }
  // Both checks of a step (the SDEM engine's and the coupled one) allow dt up to this factor
  // times their critical step (SdemEngine::setTimeStepCheckFactor).
  double checkFactor() const { return checkFactor_; }
  void setCheckFactor(double f) {
    sdem_.engine().setTimeStepCheckFactor(f);
    checkFactor_ = f;
  }
  // Reads the blocks' velocities from YADE first: a restored run must see the state it continues.
  double approachStep(const bp::object& bodies) {
    sdem_.readStates(bodies);
    return sdem_.engine().approachTimeStep();
  }
  // coupling::coupledAutoStep with this scene's approach steps (critical: the caller's, which may
  // hold a restored contact step).
  double autoStep(const bp::object& bodies, double factor, double critical, double lastDt) {
    sdem_.readStates(bodies);
    terms_ = coupling::autoStepTerms(sdem_.engine(), factor, critical, contactStep(), particleApproachStep(), lastDt);
    chosen_ = true;
    return terms_.step();
  }
  // What set the last autoStep, in words (AutoStepTerms::describe); "" before the first.
  std::string stepLimit() const { return chosen_ ? terms_.describe() : ""; }
  // MpSdemCoupling::particleApproachStep of the last step, or the value a checkpoint restored
  // until the next step computes its own.
  double particleApproachStep() const {
    return std::isnan(restoredApproach_)
               ? std::min(coupling_.particleApproachStep(), levelSets_.particleApproachStep())
               : restoredApproach_;
  }
  void setParticleApproachStep(double s) {
    if (!(s > 0)) throwParameter("particleApproachStep", s, "s", "> 0 (inf: no particle closing on a block)");
    restoredApproach_ = s;
  }

 private:
  // Pose and motion of the LevelSet bodies from YADE, at the state the step starts from. Torques
  // act about state.pos, the grid frame's origin, which YADE integrates about.
  void readLevelSets(const bp::object& bodies) {
    for (int i = 0; i < levelSets_.numBodies(); ++i) {
      if (lsStates_[i].is_none()) {
        lsBodies_[i] = bodies[levelSets_.externalId(i)];
        lsStates_[i] = lsBodies_[i].attr("state");
      }
      const bp::object& st = lsStates_[i];
      const Vec3 inertia = bp::extract<Vec3>(st.attr("inertia"));
      levelSets_.setState(i, bp::extract<Vec3>(st.attr("pos")), bp::extract<Quat>(st.attr("ori")),
                          bp::extract<Vec3>(st.attr("vel")), bp::extract<Vec3>(st.attr("angVel")),
                          bp::extract<double>(st.attr("mass")), inertia.minCoeff(),
                          !bp::extract<bool>(lsBodies_[i].attr("dynamic")));
    }
  }
  // The LevelSet bodies' contacts, after the SDEM coupling's (their particle forces add to its),
  // before the flow's step is queued; then, with the blocks, their forces and torques to O.forces.
  void runLevelSetContacts(double dt) {
    mpm::MpmSolver& solver = mpm_.solver();
    levelSets_.computeForces(solver.numParticles() > 0 ? solver.extendForceBuffer() : mpm::ParticleView{}, dt,
                             solver.time(), sdem_.engine().timeStepSafety(), solver.params().dx);
  }
  void levelSetForces(const bp::object& forces) {
    bp::object addF = forces.attr("addF"), addT = forces.attr("addT");
    for (int i = 0; i < levelSets_.numBodies(); ++i) {
      if (levelSets_.contactCount(i) == 0) continue;
      addF(levelSets_.externalId(i), levelSets_.force(i));
      addT(levelSets_.externalId(i), levelSets_.torque(i));
    }
  }
  // Each LevelSet body's record for coupled.h5: its state now, read from YADE, and the flow's
  // action on it in the last step.
  std::vector<coupling::OtherBodyRecord> levelSetRecords(const bp::object& bodies) const {
    std::vector<coupling::OtherBodyRecord> out(levelSets_.numBodies());
    for (int i = 0; i < levelSets_.numBodies(); ++i) {
      const bp::object st = bodies[levelSets_.externalId(i)].attr("state");
      coupling::OtherBodyRecord& r = out[i];
      r.pos = bp::extract<Vec3>(st.attr("pos"));
      r.vel = bp::extract<Vec3>(st.attr("vel"));
      r.ori = bp::extract<Quat>(st.attr("ori"));
      if (levelSets_.reported(i)) {
        r.force = levelSets_.force(i);
        r.torque = levelSets_.torque(i);
        r.contacts = levelSets_.contactCount(i);
        r.impulse = levelSets_.impulse(i);
        r.angularImpulse = levelSets_.angularImpulse(i);
        r.firstContact = levelSets_.firstContact(i);
      }
    }
    return out;
  }
  static bp::list doubleList(const std::vector<double>& values) {
    bp::list l;
    for (double v : values) l.append(v);
    return l;
  }
  // Tangential histories of a coupling as raw bytes (int64 keys, float64 xi: a restart is
  // bit-for-bit) and its slots per particle, and back.
  template <typename C>
  static bp::tuple historyBytes(const C& c) {
    const std::vector<long long> k = c.historyKeys();
    const std::vector<double> x = c.historyXi();
    return bp::make_tuple(bytes(k.data(), k.size() * sizeof(long long)), bytes(x.data(), x.size() * sizeof(double)),
                          c.historySlots());
  }
  template <typename C>
  static void setHistoryBytes(C& c, const bp::object& keys, const bp::object& xi) {
    char *kp = nullptr, *xp = nullptr;
    Py_ssize_t kn = 0, xn = 0;
    if (PyBytes_AsStringAndSize(keys.ptr(), &kp, &kn) < 0 || PyBytes_AsStringAndSize(xi.ptr(), &xp, &xn) < 0)
      bp::throw_error_already_set();
    if (kn % sizeof(long long) || xn % sizeof(double))
      throw ParameterError("checkpoint histories: byte lengths are not whole int64 / float64 arrays");
    std::vector<long long> k(kn / sizeof(long long));
    std::vector<double> x(xn / sizeof(double));
    if (kn) std::memcpy(k.data(), kp, kn);
    if (xn) std::memcpy(x.data(), xp, xn);
    c.setHistories(k, x);
  }
  bool seen(int i) const { return !(i >= coupling_.numBlocks() && i < sdem_.engine().numBodies()); }
  void requireOutput() const {
    if (!output_) throw ParameterError("output: call openOutput(dir) before writing outputs");
  }
  static bp::object bytes(const void* data, std::size_t n) {
    return bp::object(bp::handle<>(PyBytes_FromStringAndSize(static_cast<const char*>(data), static_cast<Py_ssize_t>(n))));
  }

  YadeSdemBridge& sdem_;
  PyMpm& mpm_;
  coupling::MpSdemCoupling coupling_;
  coupling::MpLevelSetCoupling levelSets_;
  std::vector<bp::object> lsStates_, lsBodies_;  // YADE's State and Body of each LevelSet body
  std::vector<Vec3> force_, torque_;
  std::vector<Quat> ori0_;  // reference orientations set by a restore before the output opens
  bool strict_ = true;
  double checkFactor_ = 1;
  double restoredApproach_ = std::numeric_limits<double>::quiet_NaN();
  coupling::AutoStepTerms terms_;  // of the last autoStep
  bool chosen_ = false;
  long warnings_ = 0;
  long steps_ = 0;
  coupling::CoupledStageSeconds stages_;  // its blocks' part is in the SDEM bridge's timings
  std::unique_ptr<coupling::CoupledOutput> output_;
};

}  // namespace

void exportCoupling() {
  bp::class_<PyCoupling, boost::noncopyable>(
      "CouplingBridge", "C++ side of mpmsdem.CoupledEngine (use that class instead).",
      bp::init<YadeSdemBridge&, PyMpm&>((bp::arg("sdem"), bp::arg("mpm")))
          [bp::with_custodian_and_ward<1, 2, bp::with_custodian_and_ward<1, 3>>()])
      .def("setPair", &PyCoupling::setPair,
           (bp::arg("material"), bp::arg("barrierStiffness"), bp::arg("friction"), bp::arg("poisson"),
            bp::arg("normalDamping"), bp::arg("tangentialDamping")))
      .def("step", &PyCoupling::step)
      .def("addLevelSet", &PyCoupling::addLevelSet,
           (bp::arg("id"), bp::arg("min"), bp::arg("spacing"), bp::arg("nx"), bp::arg("ny"), bp::arg("nz"),
            bp::arg("distField"), bp::arg("barrierStiffness"), bp::arg("friction"), bp::arg("poisson"),
            bp::arg("normalDamping"), bp::arg("tangentialDamping")))
      .add_property("numLevelSets", &PyCoupling::numLevelSets)
      .def("levelSetForce", &PyCoupling::levelSetForce)
      .def("levelSetImpulse", &PyCoupling::levelSetImpulse)
      .def("levelSetAngularImpulse", &PyCoupling::levelSetAngularImpulse)
      .def("levelSetFirstContact", &PyCoupling::levelSetFirstContact)
      .def("levelSetTorque", &PyCoupling::levelSetTorque)
      .def("levelSetContactCount", &PyCoupling::levelSetContactCount)
      .def("levelSetContacts", &PyCoupling::levelSetContacts)
      .def("force", &PyCoupling::force)
      .def("torque", &PyCoupling::torque)
      .def("impulse", &PyCoupling::impulse)
      .def("angularImpulse", &PyCoupling::angularImpulse)
      .def("firstContact", &PyCoupling::firstContact)
      .def("faceForce", &PyCoupling::faceForce)
      .def("edgeForce", &PyCoupling::edgeForce)
      .def("contactCount", &PyCoupling::contactCount)
      .def("contacts", &PyCoupling::contacts)
      .def("energies", &PyCoupling::energies)
      .def("timings", &PyCoupling::timings)
      .def("resetTimings", &PyCoupling::resetTimings)
      .def("openOutput", &PyCoupling::openOutput)
      .def("outsideGridWarnings", &PyCoupling::outsideGridWarnings)
      .def("checkBlockSpeeds", &PyCoupling::checkBlockSpeeds)
      .add_property("defaultMaxBlockSpeed", &PyCoupling::defaultMaxBlockSpeed)
      .def("commitOutput", &PyCoupling::commitOutput)
      .def("record", &PyCoupling::record)
      .def("appendSeries", &PyCoupling::appendSeries)
      .def("writeVtk", &PyCoupling::writeVtk)
      .def("criticalTimeStep", &PyCoupling::criticalTimeStep)
      .def("histories", &PyCoupling::histories)
      .def("setHistories", &PyCoupling::setHistories)
      .def("blockDissipation", &PyCoupling::blockDissipation)
      .def("setDissipation", &PyCoupling::setDissipation)
      .def("blockImpulses", &PyCoupling::blockImpulses)
      .def("setImpulses", &PyCoupling::setImpulses)
      .def("levelSetImpulses", &PyCoupling::levelSetImpulses)
      .def("setLevelSetImpulses", &PyCoupling::setLevelSetImpulses)
      .def("blockFirstContacts", &PyCoupling::blockFirstContacts)
      .def("setFirstContacts", &PyCoupling::setFirstContacts)
      .def("levelSetFirstContacts", &PyCoupling::levelSetFirstContacts)
      .def("setLevelSetFirstContacts", &PyCoupling::setLevelSetFirstContacts)
      .def("levelSetHistories", &PyCoupling::levelSetHistories)
      .def("setLevelSetHistories", &PyCoupling::setLevelSetHistories)
      .def("levelSetDissipation", &PyCoupling::levelSetDissipation)
      .def("setLevelSetDissipation", &PyCoupling::setLevelSetDissipation)
      .def("referenceOrientations", &PyCoupling::referenceOrientations)
      .def("setReferenceOrientations", &PyCoupling::setReferenceOrientations)
      .add_property("contactStep", &PyCoupling::contactStep)
      .add_property("totalContacts", &PyCoupling::totalContacts)
      .add_property("historyOverflow", &PyCoupling::historyOverflow)
      .add_property("historySlots", &PyCoupling::historySlots, &PyCoupling::setHistorySlots)
      .add_property("recordContacts", &PyCoupling::recordContacts, &PyCoupling::setRecordContacts)
      .add_property("strict", &PyCoupling::strict, &PyCoupling::setStrict)
      .add_property("checkFactor", &PyCoupling::checkFactor, &PyCoupling::setCheckFactor)
      .def("approachStep", &PyCoupling::approachStep)
      .def("autoStep", &PyCoupling::autoStep)
      .add_property("stepLimit", &PyCoupling::stepLimit)
      .add_property("particleApproachStep", &PyCoupling::particleApproachStep, &PyCoupling::setParticleApproachStep)
      .add_property("timeStepWarnings", &PyCoupling::warnings);
}

}  // namespace py
}  // namespace mpmsdem
