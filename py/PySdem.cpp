// Binding of the SDEM engine and its YADE bridge (py/PySdem.hpp).
#include "PySdem.hpp"

#include "input/MeshReader.hpp"

namespace mpmsdem {
namespace py {

namespace {

void validateMaterial(const SdemMaterial& m) { m.validate(); }

// The vertices and triangles SpheroPolyhedron.meshFile builds its shape from: a checkpoint
// stores them, so that it restores the same shape (same feature indices) without the file.
bp::tuple readMeshFile(const std::string& path, double scale) {
  const io::TriangleMesh m = io::readMesh(path, scale);
  bp::list v, t;
  for (const Vec3& x : m.vertices) v.append(bp::make_tuple(x[0], x[1], x[2]));
  for (const auto& tr : m.triangles) t.append(bp::make_tuple(tr[0], tr[1], tr[2]));
  return bp::make_tuple(v, t);
}

// A restart from a checkpoint taken at `time`: the HDF5 file goes back to its copy of the
// last commit (io::resumeFromCommit; the killed run may have left the file itself damaged),
// then records, snapshots and ParaView entries later than `time` were written by the run that
// went on past the checkpoint and are dropped, so that the continued run appends without
// duplicates or steps back in time. Either path may be empty or name a file that does not
// exist yet (nothing to do). Returns (time of the last series record kept or NaN, snapshots
// kept, time of the last .pvd entry kept or NaN).
bp::tuple truncateOutputsAfter(const std::string& h5, const std::string& pvd, double time) {
  namespace fs = std::filesystem;
  double lastRecord = std::nan("");
  long snapshots = 0;
  double lastVtk = std::nan("");
  if (!h5.empty() && (io::resumeFromCommit(h5) || fs::exists(h5))) {
    const bool snapshotFiles = fs::is_directory(fs::path(h5).parent_path() / io::snapshotFolder(h5));
    io::Hdf5Writer w(h5, io::Hdf5Writer::Mode::Append, snapshotFiles);
    w.truncateSeriesAfter("time", time, &lastRecord);
    snapshots = w.dropSnapshotsAfter(time);
  }
  if (!pvd.empty() && std::filesystem::exists(pvd)) lastVtk = io::PvdCollection(pvd, true).dropAfter(time);
  return bp::make_tuple(lastRecord, snapshots, lastVtk);
}

}  // namespace

void exportSdem() {
  bp::def("truncateOutputsAfter", &truncateOutputsAfter, (bp::arg("h5"), bp::arg("pvd"), bp::arg("time")),
          "Restore the HDF5 file's last commit, then drop its series records, snapshots and the .pvd entries "
          "later than time [s] (a restart).");
  bp::def("readMeshFile", &readMeshFile, (bp::arg("path"), bp::arg("scale") = 1.0),
          "(vertices, triangles) of an STL/OBJ file as SpheroPolyhedron.meshFile reads it [m].");
  bp::class_<SdemMaterial>("SdemMat",
                           "Contact material of a sphero-polyhedron block (paper Eqs 9-11). SI units.")
      .def_readwrite("density", &SdemMaterial::density, "Mass density [kg/m^3], > 0.")
      .def_readwrite("friction", &SdemMaterial::friction, "Coulomb friction coefficient mu [-], >= 0 (Eq 9).")
      .def_readwrite("poisson", &SdemMaterial::poisson, "Poisson ratio nu [-], in (-1, 0.5); K_t = k_n/(2(1+nu)) (Eq 11).")
      .def_readwrite("barrierStiffness", &SdemMaterial::barrierStiffness,
                     "Barrier stiffness k_c [N/m], > 0 (Eq 10 as a force; paper 1e4).")
      .def_readwrite("normalDamping", &SdemMaterial::normalDamping,
                     "Normal damping, fraction of critical [-], >= 0 (default 0: elastic barrier).")
      .def_readwrite("tangentialDamping", &SdemMaterial::tangentialDamping,
                     "Tangential damping c_t, fraction of critical [-], >= 0 (Eq 9).")
      .def("validate", &validateMaterial, "Raise ValueError naming the first parameter out of range.");

  bp::class_<YadeSdemBridge, boost::noncopyable>("SdemBridge",
                                                 "C++ side of mpmsdem.SdemEngine (use that class instead).")
      .def("addMaterial", &YadeSdemBridge::addMaterial)
      .def("setTerrain", &YadeSdemBridge::setTerrain)
      .def("addBody", &YadeSdemBridge::addBody)
      .def("refresh", &YadeSdemBridge::refresh)
      .def("step", &YadeSdemBridge::step)
      .def("rollBack", &YadeSdemBridge::rollBack)
      .def("setStepClock", &YadeSdemBridge::setStepClock)
      .def("setDissipation", &YadeSdemBridge::setDissipation)
      .add_property("goodTime", &YadeSdemBridge::goodTime)
      .def("timings", &YadeSdemBridge::timings)
      .def("resetTimings", &YadeSdemBridge::resetTimings)
      .def("contacts", &YadeSdemBridge::contacts)
      .def("histories", &YadeSdemBridge::histories)
      .def("openOutput", &YadeSdemBridge::openOutput)
      .def("commitOutput", &YadeSdemBridge::commitOutput)
      .def("record", &YadeSdemBridge::record)
      .def("recordCurrent", &YadeSdemBridge::recordCurrent)
      .def("writeVtk", &YadeSdemBridge::writeVtk)
      .def("setHistories", &YadeSdemBridge::setHistories)
      .def("force", &YadeSdemBridge::force)
      .def("torque", &YadeSdemBridge::torque)
      .def("yadeId", &YadeSdemBridge::yadeId)
      .add_property("numBodies", &YadeSdemBridge::numBodies)
      .add_property("numContacts", &YadeSdemBridge::numContacts)
      .add_property("narrowPhasePairs", &YadeSdemBridge::narrowPhasePairs)
      .add_property("criticalTimeStep", &YadeSdemBridge::criticalTimeStep)
      .def("autoStep", &YadeSdemBridge::autoStep)
      .add_property("checkFactor", &YadeSdemBridge::checkFactor, &YadeSdemBridge::setCheckFactor)
      .add_property("timeStepSafety", &YadeSdemBridge::timeStepSafety, &YadeSdemBridge::setTimeStepSafety)
      .add_property("strict", &YadeSdemBridge::strict, &YadeSdemBridge::setStrict)
      .add_property("maxSpeed", &YadeSdemBridge::maxSpeed, &YadeSdemBridge::setMaxSpeed)
      .add_property("timeStepWarnings", &YadeSdemBridge::warnings)
      .add_property("barrierEnergy", &YadeSdemBridge::barrierEnergy)
      .add_property("tangentialEnergy", &YadeSdemBridge::tangentialEnergy)
      .add_property("frictionDissipation", &YadeSdemBridge::frictionDissipation)
      .add_property("dampingDissipation", &YadeSdemBridge::dampingDissipation);
}

}  // namespace py
}  // namespace mpmsdem
