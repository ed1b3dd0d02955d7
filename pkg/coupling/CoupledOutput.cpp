#include "coupling/CoupledOutput.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>

#include "common/Error.hpp"
#include "coupling/LevelSetSurface.hpp"

namespace mpmsdem {
namespace coupling {

namespace fs = std::filesystem;

namespace {
std::string prepare(const std::string& dir) {
  fs::create_directories(fs::path(dir) / "vtk");
  return (fs::path(dir) / "coupled.h5").string();
}
}  // namespace

CoupledOutput::CoupledOutput(const std::string& dir, bool append, const sdem::SdemEngine& engine,
                             const std::vector<int>& otherIds)
    : dir_(dir),
      h5_(prepare(dir), append ? io::Hdf5Writer::Mode::Append : io::Hdf5Writer::Mode::Truncate),
      pvd_((fs::path(dir) / "scene.pvd").string(), append),
      others_(otherIds.size()) {
  std::vector<int> all;
  for (int i = 0; i < engine.numBodies(); ++i) all.push_back(engine.externalId(i));
  all.insert(all.end(), otherIds.begin(), otherIds.end());
  auto list = [](const std::vector<int>& v) {
    std::ostringstream os;
    os << "[";
    for (std::size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v[i];
    os << "]";
    return os.str();
  };
  // A run continued from a checkpoint written before the impulses (or the first contacts) were
  // recorded: the records before it get NaN rows, so that every series keeps a row per record
  // (the impulse then counts from the restart).
  const long before = append ? h5_.seriesLength("time") : 0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const char* name : {"flow_impulse", "flow_angular_impulse"})
    if (before > 0 && h5_.seriesLength(name) == 0)
      for (long r = 0; r < before; ++r) h5_.appendVector(name, std::vector<double>(3 * all.size(), nan));
  if (before > 0 && h5_.seriesLength("flow_first_contact") == 0)
    for (long r = 0; r < before; ++r) h5_.appendVector("flow_first_contact", std::vector<double>(all.size(), nan));
  h5_.setAttribute("ids", list(all));
  if (!otherIds.empty()) h5_.setAttribute("levelset_ids", list(otherIds));
  h5_.setAttribute("units",
                   "SI: m, s, N, N m, J, rad. Per-block series are (records, 3 x blocks) in the order of the "
                   "attribute ids: pos, vel, rotation (rotation vector from the reference orientation), "
                   "flow_force F_t, face_force F_f, edge_force F_e, flow_torque (of the step before the record), "
                   "flow_impulse, flow_angular_impulse (summed over the steps since the run's start: their change "
                   "between records over the interval is the mean force between them); contacts, flow_first_contact "
                   "(the start of the first step whose flow force on the block was not zero, NaN before) (records, "
                   "blocks). "
                   "LevelSet bodies (attribute levelset_ids) follow the blocks, with F_f and F_e NaN");
}

void CoupledOutput::dropAfter(double t) {
  h5_.truncateSeriesAfter("time", t);
  pvd_.dropAfter(t);
}

void CoupledOutput::record(double time, long step, const sdem::SdemEngine& e, const MpSdemCoupling& coupling,
                           const std::vector<OtherBodyRecord>& others) {
  if (others.size() != others_)
    throwParameter("others", others.size(), "", "one record per LevelSet body of the output (" +
                                                    std::to_string(others_) + ")");
  // blocks the coupling has not seen yet (before the first step) have no flow force
  const int nb = e.numBodies(), seen = std::min(nb, coupling.numBlocks());
  const int n = nb + static_cast<int>(others.size());
  auto orientation = [&](int i) { return i < nb ? e.orientation(i) : others[i - nb].ori; };
  for (int i = static_cast<int>(ori0_.size()); i < n; ++i) ori0_.push_back(orientation(i));
  std::vector<double> pos(3 * n), vel(3 * n), rot(3 * n), ft(3 * n), ff(3 * n), fe(3 * n), tq(3 * n), imp(3 * n),
      angImp(3 * n), cnt(n), first(n);
  const Vec3 none = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  for (int i = 0; i < n; ++i) {
    const Eigen::AngleAxis<double> aa(orientation(i) * ori0_[i].conjugate());
    const Vec3 rv = aa.angle() * aa.axis();
    const bool block = i < nb, s = i < seen;
    const OtherBodyRecord* o = block ? nullptr : &others[i - nb];
    const Vec3 x = block ? e.position(i) : o->pos, v = block ? e.velocity(i) : o->vel;
    const Vec3 f = block ? (s ? coupling.force(i) : Vec3::Zero()) : o->force,
               a = block ? (s ? coupling.faceForce(i) : Vec3::Zero()) : none,
               b = block ? (s ? coupling.edgeForce(i) : Vec3::Zero()) : none,
               t = block ? (s ? coupling.torque(i) : Vec3::Zero()) : o->torque,
               jf = block ? (s ? coupling.impulse(i) : Vec3::Zero()) : o->impulse,
               ja = block ? (s ? coupling.angularImpulse(i) : Vec3::Zero()) : o->angularImpulse;
    for (int k = 0; k < 3; ++k) {
      pos[3 * i + k] = x[k];
      vel[3 * i + k] = v[k];
      rot[3 * i + k] = rv[k];
      ft[3 * i + k] = f[k];
      ff[3 * i + k] = a[k];
      fe[3 * i + k] = b[k];
      tq[3 * i + k] = t[k];
      imp[3 * i + k] = jf[k];
      angImp[3 * i + k] = ja[k];
    }
    cnt[i] = block ? (s ? coupling.contactCount(i) : 0) : o->contacts;
    first[i] = block ? (s ? coupling.firstContact(i) : std::numeric_limits<double>::quiet_NaN()) : o->firstContact;
  }
  h5_.appendScalar("time", time);
  h5_.appendScalar("step", static_cast<double>(step));
  h5_.appendVector("pos", pos);
  h5_.appendVector("vel", vel);
  h5_.appendVector("rotation", rot);
  h5_.appendVector("flow_force", ft);
  h5_.appendVector("face_force", ff);
  h5_.appendVector("edge_force", fe);
  h5_.appendVector("flow_torque", tq);
  h5_.appendVector("flow_impulse", imp);
  h5_.appendVector("flow_angular_impulse", angImp);
  h5_.appendVector("contacts", cnt);
  h5_.appendVector("flow_first_contact", first);
}

std::vector<io::RigidSurface> bodySurfaces(const sdem::SdemEngine& engine) {
  std::vector<io::RigidSurface> bodies(engine.numBodies());
  for (int i = 0; i < engine.numBodies(); ++i) {
    const auto& shape = engine.shape(i);
    io::RigidSurface& b = bodies[i];
    b.id = engine.externalId(i);
    for (const Vec3& v : shape.outerVertices) {
      const Vec3 w = engine.position(i) + engine.orientation(i) * v;
      b.vertices.push_back({w[0], w[1], w[2]});
    }
    b.triangles = shape.outerTriangles;
  }
  return bodies;
}

void CoupledOutput::writeVtk(double time, mpm::ParticleSlices& particles, const sdem::SdemEngine& engine,
                             const MpSdemCoupling& coupling, const MpLevelSetCoupling* levelSets) {
  const std::size_t k = pvd_.count(0);
  auto file = [k](const char* what) {
    std::ostringstream f;
    f << "vtk/scene_" << what << "_" << std::setw(6) << std::setfill('0') << k << ".vtp";
    return f.str();
  };
  const int nLevelSets = levelSets ? levelSets->numBodies() : 0;
  // a body's grid never changes: its surface is traced once and moved with the body
  for (int i = static_cast<int>(levelSetLocal_.size()); i < nLevelSets; ++i)
    levelSetLocal_.push_back(levelSetSurface(levelSets->grid(i), levelSets->externalId(i)));
  std::vector<io::RigidSurface> surfaces = bodySurfaces(engine);
  for (int i = 0; i < nLevelSets; ++i)
    surfaces.push_back(placedSurface(levelSetLocal_[i], levelSets->position(i), levelSets->rotation(i)));
  io::writeParticlesVtp((fs::path(dir_) / file("particles")).string(), particles);
  io::writeRigidSurfacesVtp((fs::path(dir_) / file("bodies")).string(), surfaces);
  pvd_.add(time, file("particles"), 0);
  pvd_.add(time, file("bodies"), 1);
  if (!coupling.contactsAvailable()) return;
  std::vector<io::ContactPoint> points;
  const auto add = [&points](const MpContactRecord& r, int bodyId) {
    io::ContactPoint c;
    for (int d = 0; d < 3; ++d) {
      c.point[d] = r.point[d];
      c.force[d] = r.force[d];
    }
    c.normalForce = r.normalForce;
    c.blockId = bodyId;
    c.particle = r.particle;
    c.feature = r.featureKind;
    points.push_back(c);
  };
  for (const MpContactRecord& r : coupling.contacts()) add(r, engine.externalId(r.block));
  if (nLevelSets > 0)
    for (const MpContactRecord& r : levelSets->contacts()) add(r, levelSets->externalId(r.block));
  io::writeContactsVtp((fs::path(dir_) / file("contacts")).string(), points);
  pvd_.add(time, file("contacts"), 2);
}

}  // namespace coupling
}  // namespace mpmsdem
