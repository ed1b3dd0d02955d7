// Binding of the MPM solver (py/PyMpm.hpp).
#include "PyMpm.hpp"

#include "input/TerrainRaster.hpp"

namespace mpmsdem {
namespace py {

namespace {

bool cudaAvailable() { return mpm::cudaAvailable(); }
std::string sceneOf(const std::string& path) { return io::readStringAttribute(path, "parameters"); }

bp::dict readEsriAscii(const std::string& path) {
  const io::TerrainRaster r = io::readEsriAscii(path);
  bp::dict d;
  d["nx"] = r.nx;
  d["ny"] = r.ny;
  d["x0"] = r.x0;
  d["y0"] = r.y0;
  d["spacing"] = r.spacing;
  d["heights"] = numpyArray(r.heights.data(), r.nx, r.ny);
  return d;
}

}  // namespace

void exportMpm() {
  bp::def("cudaAvailable", &cudaAvailable, "True when this build has CUDA and a GPU is present.");
  bp::def("sceneOf", &sceneOf, (bp::arg("path")), "The scene JSON stored in an mpm.h5 or checkpoint file.");
  bp::def("readEsriAscii", &readEsriAscii, (bp::arg("path")),
          "An ESRI ASCII grid as {nx, ny, x0, y0, spacing, heights}: heights[i, j] at (x0 + i spacing, y0 + j "
          "spacing), i west to east, j south to north, at the cell centres (the driver's reader).");
  bp::class_<PyMpm, boost::noncopyable>("MpmSolver",
                                        "MPM solver built from a JSON scene (use mpmsdem.MpmEngine instead).",
                                        bp::init<std::string>(bp::arg("sceneJson")))
      .def("step", &PyMpm::step, (bp::arg("dt")))
      .def("run", &PyMpm::run, (bp::arg("steps"), bp::arg("dt")))
      .def("stableTimeStep", &PyMpm::stableTimeStep)
      .def("flipDampingRate", &PyMpm::flipDampingRate, (bp::arg("dt")),
           "PIC damping rate of a step of length dt [1/s], -ln(blend)/dt: the same at every dt unless the blend is "
           "per step (flip_reference_dt \"step\").")
      .def("flipViscosity", &PyMpm::flipViscosity, (bp::arg("dt")),
           "PIC viscosity of the blend at a step of length dt [m^2/s]: its damping rate times dx^2/4, the same at "
           "every dt unless the blend is per step.")
      .add_property("flipBlend", &PyMpm::flipBlend,
                    "The FLIP/PIC blend in words, e.g. 'PIC viscosity 0.005 m^2/s (PIC damping 200 /s at dx 0.01 m)'.")
      .def("setExternalForces", &PyMpm::setExternalForces, (bp::arg("forces")))
      .def("gateImpulse", &PyMpm::gateImpulse,
           "Impulse the scene's gate has given the material since the solver was built [N s] (x: minus the push of "
           "the material on the gate); ValueError without a gate.")
      .def("gateEdgeHeight", &PyMpm::gateEdgeHeight, (bp::arg("t")),
           "Height of the gate's lower edge at time t [m], inf once removed; ValueError without a gate.")
      .def("particles", &PyMpm::particles)
      .def("diagnostics", &PyMpm::diagnostics,
           "Whole-system diagnostics of the current state (what the series record): kinetic_energy and "
           "potential_energy [J] (zero height at the origin), front_x and height_z [m], centre_of_mass [m], "
           "max_speed [m/s], flowing_fraction and gasified_fraction; read from the solver a slice at a time.")
      .def("openOutput", &PyMpm::openOutput, (bp::arg("dir"), bp::arg("append") = false))
      .def("writeSnapshot", &PyMpm::writeSnapshot)
      .def("appendSeries", &PyMpm::appendSeries, (bp::arg("name"), bp::arg("value")))
      .def("appendVector", &PyMpm::appendVector, (bp::arg("name"), bp::arg("values")))
      .def("saveCheckpoint", &PyMpm::saveCheckpoint, (bp::arg("path")))
      .def("loadSnapshot", &PyMpm::loadSnapshot, (bp::arg("path"), bp::arg("index") = -1))
      .add_property("time", &PyMpm::time)
      .add_property("steps", &PyMpm::steps)
      .add_property("numParticles", &PyMpm::numParticles)
      .add_property("memoryBytes", &PyMpm::memoryBytes)
      .add_property("holdsLastGoodState", &PyMpm::holdsLastGoodState,
                    "False once a step failed with keepLastGoodState off: the particles are partly advanced, and "
                    "the solver refuses to step or give them out (the last snapshot saved is the last good state).")
      .add_property("name", &PyMpm::name)
      .add_property("sceneJson", &PyMpm::sceneJson)
      .add_property("gravity", &PyMpm::gravity, "Gravity of the scene [m/s^2] (an incline resolved).");
}

}  // namespace py
}  // namespace mpmsdem
