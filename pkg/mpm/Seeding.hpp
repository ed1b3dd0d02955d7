// Seeding material points on a regular sub-lattice of the grid cells, in an axis-aligned box
// region (seedBox) or inside a closed triangle mesh (seedMesh).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "common/Types.hpp"
#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace mpm {

// Appends to `out` the material points of the box [lo, hi] (m): each grid cell (of spacing
// params.dx, aligned with params.origin) whose centre lies in the box receives perAxis[0] x
// perAxis[1] x perAxis[2] points at the centres of an equal subdivision of the cell (each
// perAxis in [1, 8]). Each point gets mass rho_0 dx^3 / n (n = product of perAxis, rho_0 =
// params.material.density), volume0 dx^3 / n, J = 1, zero velocity, stress and force,
// phase 0. Throws ParameterError when the box is empty, not inside the admissible particle
// box (the grid domain less its kWallLayer-cell wall layers), or perAxis is out of range.
// Returns the number of points added.
std::size_t seedBox(const MpmParams& params, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    const std::array<int, 3>& perAxis, ParticleSet& out);

// Where seeded points go: each point at x [m] with its mass [kg], initial volume [m^3] and
// velocity [m/s]; everything else starts at rest (zero stress and force, J = 1, phase 0).
class SeedSink {
 public:
  virtual ~SeedSink() = default;
  virtual void add(const double x[3], double mass, double volume0, const std::array<double, 3>& velocity) = 0;
};

// Appends to a ParticleSet.
class ParticleSetSink : public SeedSink {
 public:
  explicit ParticleSetSink(ParticleSet& out) : out_(out) {}
  void add(const double x[3], double mass, double volume0, const std::array<double, 3>& velocity) override;

 private:
  ParticleSet& out_;
};

// Seeded points held compactly: their positions (24 B per point) and runs of points that share
// mass, volume and velocity; handed out as full particle slices (what MpmSolver::setParticles
// reads), so a scene is seeded without a whole ParticleSet (145 B per point) on the host.
class SeededParticles : public SeedSink, public ParticleSlices {
 public:
  void add(const double x[3], double mass, double volume0, const std::array<double, 3>& velocity) override;
  std::size_t size() const override { return x_.size() / 3; }
  std::size_t sliceSize() const override { return 1 << 16; }
  const ParticleSet& slice(std::size_t first, std::size_t count) override;
  // Release the growth reserve of the positions once seeding is done.
  void shrink() { x_.shrink_to_fit(); }

 private:
  struct Run {
    std::size_t first;
    double mass, volume0;
    std::array<double, 3> velocity;
  };
  std::vector<double> x_;
  std::vector<Run> runs_;
  ParticleSet buffer_;
};

// seedBox and seedMesh into any sink, the box's points with `velocity`.
std::size_t seedBox(const MpmParams& params, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    const std::array<int, 3>& perAxis, const std::array<double, 3>& velocity, SeedSink& out);

// Same with n points per cell, n a perfect cube (1, 8, 27, ...): n^(1/3) per axis.
std::size_t seedBox(const MpmParams& params, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    int perCell, ParticleSet& out);

// Generalized winding number of the triangle surface (vertices [m], triangles as vertex
// indices) about the point p [m]: the sum of the signed solid angles of the triangles seen
// from p, divided by 4 pi. For a closed surface whose triangles are counter-clockwise seen
// from outside it is 1 inside, 0 outside (-1 inside for the opposite orientation); small
// defects (a tiny hole, a sliver) change it only by the solid angle they subtend.
// Triangles with a repeated vertex index contribute nothing. Indices must be valid.
double windingNumber(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles,
                     const Vec3& p);

// Axis-aligned bounding box and enclosed volume of a mesh accepted by seedMesh.
struct MeshBounds {
  std::array<double, 3> lo{0, 0, 0};  // lower corner [m]
  std::array<double, 3> hi{0, 0, 0};  // upper corner [m]
  double volume = 0;                  // signed enclosed volume [m^3]: > 0 when the triangles are
                                      // counter-clockwise seen from outside, < 0 when reversed
};

// Checks that a triangle mesh can be seeded in the grid of `params` and returns its bounds.
// `name` (e.g. the file) labels the mesh in messages. Throws ParameterError, each message
// starting with "mesh '<name>'", when: there are no triangles; a vertex index is outside
// [0, vertices - 1]; a coordinate is not finite; the mesh is not closed (some edge is not
// shared by exactly 2 triangles, with opposite directions: a consistently oriented,
// watertight, edge-manifold surface); the enclosed volume is not above 1e-9 times the cube
// of the bounding-box diagonal (no volume); the bounding box is not inside the material
// region [origin + kWallLayer dx, origin + (cells - kWallLayer) dx] (the message gives it).
// Triangles with a repeated vertex index (zero area, e.g. after duplicate vertices were
// merged) are ignored.
MeshBounds checkSeedMesh(const MpmParams& params, const std::vector<Vec3>& vertices,
                         const std::vector<std::array<int, 3>>& triangles, const std::string& name);

// Appends to `out` the material points inside a closed triangle mesh (vertices [m] in grid
// coordinates, triangles as vertex indices; either orientation). Candidates are the points
// seedBox uses, perAxis[0] x perAxis[1] x perAxis[2] per cell (each perAxis in [1, 8]), over
// the grid cells covering the mesh's bounding box; a candidate is kept when it lies inside
// the mesh. Each kept point gets mass rho_0 dx^3 / n (n = product of perAxis), volume0
// dx^3 / n, J = 1, the given velocity [m/s], zero stress and force, phase 0; points come in
// the same order as seedBox's (cell x, y, z, then sub-cell x, y, z), so a box-shaped mesh
// with faces on grid lines gives exactly seedBox's points.
//
// Inside test: for every vertical line of candidates, the crossings of the line with the
// triangles (found through a per-cell bucketing of the triangles' xy bounding boxes) are
// counted below each candidate (ray parity, O(crossings) per line, lines in parallel with
// OpenMP). Where that is not robust -- the line passes within round-off of a triangle edge
// or vertex or lies in a vertical face, the line has an odd number of crossings, or a
// candidate lies within round-off of a crossing -- the candidate is decided by the
// generalized winding number instead (windingNumber, inside when > 1/2 in the mesh's own
// orientation), which is exact for closed meshes and costs O(triangles) per candidate.
//
// Throws ParameterError (message naming the mesh) for the cases of checkSeedMesh, for
// perAxis out of range, and when no candidate is inside (the mesh thinner than the point
// spacing dx / perAxis). `name` labels the mesh in messages. Returns the number of points added.
std::size_t seedMesh(const MpmParams& params, const std::vector<Vec3>& vertices,
                     const std::vector<std::array<int, 3>>& triangles, const std::array<int, 3>& perAxis,
                     const std::array<double, 3>& velocity, ParticleSet& out, const std::string& name = "mesh");
std::size_t seedMesh(const MpmParams& params, const std::vector<Vec3>& vertices,
                     const std::vector<std::array<int, 3>>& triangles, const std::array<int, 3>& perAxis,
                     const std::array<double, 3>& velocity, SeedSink& out, const std::string& name = "mesh");

}  // namespace mpm
}  // namespace mpmsdem
