// The MPM solver's binding class (C++ side of mpmsdem.MpmEngine), shared by its binding
// (PyMpm.cpp) and the coupled engine's (PyCoupling.cpp): a scene (the same JSON schema as the
// mpmsdem-run driver, see examples/scenes/README.md), stepping, particle arrays, HDF5 + VTK
// outputs.
#pragma once
#include <filesystem>
#include <iomanip>
#include <iterator>
#include <memory>
#include <new>
#include <sstream>

#include "PyConvert.hpp"
#include "io/Hdf5Writer.hpp"
#include "io/VtkWriter.hpp"
#include "mpm/Diagnostics.hpp"
#include "mpm/Gate.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"

namespace mpmsdem {
namespace py {

class PyMpm {
 public:
  explicit PyMpm(const std::string& sceneJson) : scene_(mpm::parseScene(sceneJson, "MpmEngine scene")) {
    try {
      solver_ = mpm::makeSolver(scene_.params, scene_.run.backend, scene_.run.precision);
      mpm::SeededParticles seeded = mpm::seedParticleSlices(scene_);
      solver_->setParticles(seeded);
      slices_ = std::make_unique<mpm::SolverParticleSlices>(*solver_, 1 << 16);
    } catch (const std::bad_alloc&) {
      throw ParameterError("out of memory for " + mpm::sceneSizeDescription(scene_) +
                           ": reduce grid.cells (a coarser dx or a smaller domain) or the particles per cell (ppc)");
    }
  }

  void step(double dt) { solver_->step(dt); }
  void run(long n, double dt) {
    for (long i = 0; i < n; ++i) solver_->step(dt);
  }
  bool holdsLastGoodState() const { return solver_->holdsLastGoodState(); }
  double stableTimeStep() { return solver_->stableTimeStep(); }
  std::string flipBlend() const { return scene_.params.flip.describe(scene_.params.dx); }
  double flipDampingRate(double dt) const { return scene_.params.flip.dampingRate(dt, scene_.params.dx); }
  double flipViscosity(double dt) const { return scene_.params.flip.viscosityFor(dt, scene_.params.dx); }
  double time() const { return solver_->time(); }
  long steps() const { return solver_->steps(); }
  std::size_t numParticles() const { return solver_->numParticles(); }
  std::size_t memoryBytes() const { return solver_->memoryBytes(); }
  std::string name() const { return solver_->name(); }
  std::string sceneJson() const { return scene_.sourceJson; }
  mpm::MpmSolver& solver() { return *solver_; }
  bp::tuple gravity() const {
    const auto& g = scene_.params.gravity;
    return bp::make_tuple(g[0], g[1], g[2]);
  }

  // The scene's gate: impulse it has given the material since the solver was built [N s],
  // and the height of its lower edge at time t [m] (inf once removed).
  bp::tuple gateImpulse() const {
    const std::array<double, 3> j = gate().impulse();
    return bp::make_tuple(j[0], j[1], j[2]);
  }
  double gateEdgeHeight(double t) const { return gate().edgeHeight(t); }

  void setExternalForces(const bp::object& f) {
    solver_->setExternalForces(fromNumpy(f, 3 * solver_->numParticles(), "forces"));
  }

  // The particle state as new numpy arrays, filled from the solver slice by slice (no whole
  // host copy of the particles besides the arrays themselves).
  bp::dict particles() {
    const std::size_t n = solver_->numParticles();
    constexpr std::size_t kColumns = std::size(mpm::kParticleColumns);
    double* data[kColumns];
    bp::dict d;
    for (std::size_t k = 0; k < kColumns; ++k) {
      const mpm::ParticleColumn& c = mpm::kParticleColumns[k];
      const npy_intp cols = c.values == 1 ? 0 : static_cast<npy_intp>(c.values);  // 0: a 1-D array
      d[c.name] = numpyEmpty(static_cast<npy_intp>(n), cols, &data[k]);
    }
    mpm::forEachSlice(*slices_, [&](std::size_t first, const mpm::ParticleSet& p) {
      for (std::size_t k = 0; k < kColumns; ++k) {
        const mpm::ParticleColumn& c = mpm::kParticleColumns[k];
        double* out = data[k] + first * c.values;
        if (c.kind == mpm::ColumnKind::kState)
          std::copy((p.*c.member).begin(), (p.*c.member).end(), out);
        else
          for (std::size_t i = 0; i < p.size(); ++i)
            out[i] = c.kind == mpm::ColumnKind::kPhase ? p.phase[i] : p.density(i);
      }
    });
    return d;
  }

  // The series' diagnostics of the current state (mpm::diagnose): on CUDA reduced on the
  // device, elsewhere read slice by slice.
  bp::dict diagnostics() {
    const mpm::Diagnostics d = mpm::diagnose(*solver_, outputParticles(), scene_.params.gravity);
    bp::dict out;
    out["kinetic_energy"] = d.kineticEnergy;
    out["potential_energy"] = d.potential;
    out["front_x"] = d.frontX;
    out["height_z"] = d.heightZ;
    out["centre_of_mass"] = bp::make_tuple(d.com[0], d.com[1], d.com[2]);
    out["max_speed"] = d.maxSpeed;
    out["flowing_fraction"] = d.flowing;
    out["gasified_fraction"] = d.gasified;
    return out;
  }

  // Outputs: <dir>/mpm.h5 (append-only series + snapshots) and <dir>/vtk/particles_*.vtp + .pvd.
  void openOutput(const std::string& dir, bool append) {
    std::filesystem::create_directories(std::filesystem::path(dir) / "vtk");
    const auto mode = append ? io::Hdf5Writer::Mode::Append : io::Hdf5Writer::Mode::Truncate;
    h5_ = std::make_unique<io::Hdf5Writer>((std::filesystem::path(dir) / "mpm.h5").string(), mode, true);
    writeHeader(*h5_);
    pvd_ = std::make_unique<io::PvdCollection>((std::filesystem::path(dir) / "particles.pvd").string(), append);
    dir_ = dir;
  }
  void writeSnapshot() {
    requireOutput();
    const long k = h5_->writeSnapshot(outputParticles(), solver_->time(), solver_->steps());
    std::ostringstream name;
    name << "vtk/particles_" << std::setw(6) << std::setfill('0') << k << ".vtp";
    io::writeParticlesVtp((std::filesystem::path(dir_) / name.str()).string(), outputParticles());
    pvd_->add(solver_->time(), name.str());
  }
  void writeParticlesVtp(const std::string& path) { io::writeParticlesVtp(path, outputParticles()); }
  // The particles for an output, read from the solver slice by slice.
  mpm::ParticleSlices& outputParticles() { return *slices_; }
  // A checkpoint: one HDF5 file with the scene and the full particle state at this time
  // (the same layout as mpm.h5, so any output file also works as a checkpoint).
  void saveCheckpoint(const std::string& path) {
    if (h5_) h5_->commit();  // a restart from this checkpoint finds the outputs as they are now
    const std::string tmp = path + ".tmp";
    {
      io::Hdf5Writer w(tmp, io::Hdf5Writer::Mode::Truncate);
      writeHeader(w);
      w.writeSnapshot(outputParticles(), solver_->time(), solver_->steps());
    }
    std::filesystem::rename(tmp, path);
  }
  // Continue from snapshot `index` (-1: the last) of an mpm.h5 or checkpoint file.
  void loadSnapshot(const std::string& path, long index) {
    const long n = io::readNumSnapshots(path);
    if (index < 0) index += n;
    if (index < 0 || index >= n) throwParameter("index", index, "", "in [-" + std::to_string(n) + ", " +
                                                 std::to_string(n) + ") (snapshots in " + path + ")");
    io::SnapshotSlices snapshot(path, index);
    solver_->setParticles(snapshot);
    solver_->setClock(snapshot.time(), snapshot.step());
  }
  void appendSeries(const std::string& name, double value) {
    requireOutput();
    h5_->appendScalar(name, value);
  }
  void appendVector(const std::string& name, const bp::object& values) {
    requireOutput();
    h5_->appendVector(name, sequenceOfDoubles(values));
  }

 private:
  const mpm::Gate& gate() const {
    const mpm::Gate* g = solver_->findGridHook<mpm::Gate>();
    if (!g) throw ParameterError("gate: this scene has none (give the scene a \"gate\", MpmEngine(gate=...))");
    return *g;
  }
  void writeHeader(io::Hdf5Writer& w) const {
    io::writeMpmHeader(w, scene_.sourceJson, scene_.params, solver_->name());
  }
  void requireOutput() const {
    if (!h5_) throw ParameterError("output: call openOutput(dir) before writing outputs");
  }

  mpm::MpmScene scene_;
  std::unique_ptr<mpm::MpmSolver> solver_;
  std::unique_ptr<mpm::SolverParticleSlices> slices_;
  std::unique_ptr<io::Hdf5Writer> h5_;
  std::unique_ptr<io::PvdCollection> pvd_;
  std::string dir_;
};

}  // namespace py
}  // namespace mpmsdem
