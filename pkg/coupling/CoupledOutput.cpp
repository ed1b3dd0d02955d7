#include "coupling/CoupledOutput.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace mpmsdem {
namespace coupling {

namespace fs = std::filesystem;

namespace {
std::string prepare(const std::string& dir) {
  fs::create_directories(fs::path(dir) / "vtk");
  return (fs::path(dir) / "coupled.h5").string();
}
}  // namespace

CoupledOutput::CoupledOutput(const std::string& dir, bool append, const sdem::SdemEngine& engine)
    : dir_(dir),
      h5_(prepare(dir), append ? io::Hdf5Writer::Mode::Append : io::Hdf5Writer::Mode::Truncate),
      pvd_((fs::path(dir) / "scene.pvd").string(), append) {
  std::ostringstream ids;
  ids << "[";
  for (int i = 0; i < engine.numBodies(); ++i) ids << (i ? ", " : "") << engine.externalId(i);
  ids << "]";
  h5_.setAttribute("ids", ids.str());
  h5_.setAttribute("units",
                   "SI: m, s, N, N m, J, rad. Per-block series are (records, 3 x blocks) in the order of the "
                   "attribute ids: pos, vel, rotation (rotation vector from the reference orientation), "
                   "flow_force F_t, face_force F_f, edge_force F_e, flow_torque; contacts (records, blocks)");
}

void CoupledOutput::dropAfter(double t) {
  h5_.truncateSeriesAfter("time", t);
  pvd_.dropAfter(t);
}

void CoupledOutput::record(double time, long step, const sdem::SdemEngine& e, const MpSdemCoupling& coupling) {
  // blocks the coupling has not seen yet (before the first step) have no flow force
  const int n = e.numBodies(), seen = std::min(n, coupling.numBlocks());
  for (int i = static_cast<int>(ori0_.size()); i < n; ++i) ori0_.push_back(e.orientation(i));
  std::vector<double> pos(3 * n), vel(3 * n), rot(3 * n), ft(3 * n), ff(3 * n), fe(3 * n), tq(3 * n), cnt(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::AngleAxis<double> aa(e.orientation(i) * ori0_[i].conjugate());
    const Vec3 rv = aa.angle() * aa.axis();
    const bool s = i < seen;
    const Vec3 f = s ? coupling.force(i) : Vec3::Zero(), a = s ? coupling.faceForce(i) : Vec3::Zero(),
               b = s ? coupling.edgeForce(i) : Vec3::Zero(), t = s ? coupling.torque(i) : Vec3::Zero();
    for (int k = 0; k < 3; ++k) {
      pos[3 * i + k] = e.position(i)[k];
      vel[3 * i + k] = e.velocity(i)[k];
      rot[3 * i + k] = rv[k];
      ft[3 * i + k] = f[k];
      ff[3 * i + k] = a[k];
      fe[3 * i + k] = b[k];
      tq[3 * i + k] = t[k];
    }
    cnt[i] = s ? coupling.contactCount(i) : 0;
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
  h5_.appendVector("contacts", cnt);
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
                             const MpSdemCoupling& coupling) {
  const std::size_t k = pvd_.count(0);
  auto file = [k](const char* what) {
    std::ostringstream f;
    f << "vtk/scene_" << what << "_" << std::setw(6) << std::setfill('0') << k << ".vtp";
    return f.str();
  };
  io::writeParticlesVtp((fs::path(dir_) / file("particles")).string(), particles);
  io::writeRigidSurfacesVtp((fs::path(dir_) / file("bodies")).string(), bodySurfaces(engine));
  pvd_.add(time, file("particles"), 0);
  pvd_.add(time, file("bodies"), 1);
  if (!coupling.contactsAvailable()) return;
  std::vector<io::ContactPoint> points;
  for (const MpContactRecord& r : coupling.contacts()) {
    io::ContactPoint c;
    for (int d = 0; d < 3; ++d) {
      c.point[d] = r.point[d];
      c.force[d] = r.force[d];
    }
    c.normalForce = r.normalForce;
    c.blockId = engine.externalId(r.block);
    c.particle = r.particle;
    c.feature = r.featureKind;
    points.push_back(c);
  }
  io::writeContactsVtp((fs::path(dir_) / file("contacts")).string(), points);
  pvd_.add(time, file("contacts"), 2);
}

}  // namespace coupling
}  // namespace mpmsdem
