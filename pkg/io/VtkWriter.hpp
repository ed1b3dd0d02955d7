// VTK XML output for ParaView: particles and rigid-body surfaces as PolyData (.vtp), and a
// ParaView collection (.pvd) listing them with their times.
//
// Field values are written as Float32 (visualisation; the HDF5 output keeps full double
// precision). Each .vtp is written to "<path>.tmp" and renamed, and the .pvd is rewritten
// the same way after every added file, so a killed run leaves a valid series of complete
// files.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace io {

// Ascii: human-readable, large. AppendedRaw: binary appended section (about 5x smaller
// and faster), the default for runs.
enum class VtkEncoding { Ascii, AppendedRaw };

// Particles as points with one poly-vertex cell. Point data:
//   velocity (3) [m/s], stress (9, full symmetric tensor, tension positive) [Pa],
//   pressure (1) = -trace(stress)/3 [Pa], density (1) = mass/(J volume0) [kg/m^3],
//   gammaDotP (1) [1/s], phase (UInt8: 0 elastic, 1 flowing, 2 gasified).
// Throws ParameterError when the ParticleSet arrays have inconsistent sizes, RuntimeFailure
// when the file cannot be written.
void writeParticlesVtp(const std::string& path, const mpm::ParticleSet& particles,
                       VtkEncoding encoding = VtkEncoding::AppendedRaw);
// The same file from particles read slice by slice (AppendedRaw holds one slice at a time).
void writeParticlesVtp(const std::string& path, mpm::ParticleSlices& particles,
                       VtkEncoding encoding = VtkEncoding::AppendedRaw);

// The triangulated surface of one rigid body in world coordinates.
struct RigidSurface {
  int id = 0;                                  // body id (e.g. YADE's), written per triangle as cell data "bodyId"
  std::vector<std::array<double, 3>> vertices; // [m]
  std::vector<std::array<int, 3>> triangles;   // 0-based indices into `vertices`, outward normal by right-hand rule
};

// All bodies in one .vtp: points = all vertices, polys = all triangles, cell data "bodyId"
// (Int32). Throws ParameterError naming the body and triangle when an index is out of range.
void writeRigidSurfacesVtp(const std::string& path, const std::vector<RigidSurface>& bodies,
                           VtkEncoding encoding = VtkEncoding::AppendedRaw);

// One contact between a material point and a block (writeContactsVtp).
struct ContactPoint {
  std::array<double, 3> point{};  // contact point [m]
  std::array<double, 3> force{};  // the flow's force on the block through it [N]
  double normalForce = 0;         // F_n [N]
  int blockId = 0;                // the block's body id (e.g. YADE's)
  int particle = 0;               // the material point's number
  int feature = 0;                // the block's core feature nearest the point: 0 face, 1 edge, 2 vertex
};

// Contacts as points, one vertex cell each. Point data: force (3) [N, on the block],
// normalForce (1) [N], blockId (Int32), particle (Int32), feature (UInt8: 0 face, 1 edge,
// 2 vertex). ParaView's Glyph filter on "force" draws where and how hard the flow pushed.
void writeContactsVtp(const std::string& path, const std::vector<ContactPoint>& contacts,
                      VtkEncoding encoding = VtkEncoding::AppendedRaw);

// A ParaView .pvd collection: a list of (time, part, file) entries.
class PvdCollection {
 public:
  // append = false starts an empty collection; append = true continues the entries of an
  // existing file at `path` (restart), or starts empty when there is none.
  PvdCollection(const std::string& path, bool append = false);

  // Add a dataset and rewrite the .pvd. `file` is relative to the directory of the .pvd;
  // `part` separates several datasets at one time (e.g. 0 particles, 1 rigid bodies).
  void add(double time, const std::string& file, int part = 0);

  std::size_t size() const { return entries_.size(); }
  std::size_t count(int part) const;  // entries of one part
  // Drop the entries later than `time` (a restart from an earlier checkpoint) and rewrite
  // the .pvd; the continued run's files then take their places. Returns the time of the
  // last entry kept (NaN when none is left).
  double dropAfter(double time);

 private:
  struct Entry {
    double time;
    int part;
    std::string file;
  };
  void rewrite() const;

  std::string path_;
  std::vector<Entry> entries_;
};

}  // namespace io
}  // namespace mpmsdem
