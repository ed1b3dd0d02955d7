// Ig2_SpheroPolyhedron_Terrain: contact geometry between a sphero-polyhedron and the terrain
// (common/Terrain.hpp: a height field, linear on the two triangles of each raster cell, flat beyond
// the raster; its own sweep radius is 0, so a contact's barrier reaches the body's R from its
// core). Four feature pairs, so that relief finer than a body's core is felt and each geometric
// contact counts once:
//  - core vertex – terrain: the vertex against the plane of the triangle under it (d < R). A cube
//    face-down carries its weight on its 4 corners, edge-down on 2.
//  - core vertex – wall: the vertex against a triangle steeper than the one under it by more than
//    wallCosine (a valley wall, a cliff) whose plane is within R of it (d < R) with the foot of
//    the normal inside it, so that a block beside a wall feels it before it is over it; of
//    several such triangles nearly parallel to each other only the nearest (one slope, one
//    contact). A vertex in a corner touches the floor and the wall. A wall contact starts where
//    the foot enters the triangle, with d >= (distance to the plane under it) / wallCosine there
//    at a concave fold: no step in the force unless the vertex is pressed more than
//    (1 - wallCosine) R into the ground beside the wall.
//  - crest node – core: a raster node at an end of a convex terrain edge (a ridge or a peak; any
//    other node lies in or below the planes of its triangles, which the core's vertices meet
//    first) against the closest point of the core; left to the vertex pair when that point is a
//    core vertex that has its own terrain contact.
//  - convex terrain edge – convex core edge: the closest points of the two lines, inside both
//    edges (their ends are the pairs above), the edges not parallel, the normal in the core edge's
//    normal cone and its opposite in the terrain edge's (between its two triangles); or, where a
//    face at the core edge lies nearly flat on a triangle at the terrain edge, the crossing of the
//    two edges seen along that face's normal (a corner of their contact patch, kept while the
//    faces tilt, as Ig2_SpheroPolyhedron_SpheroPolyhedron keeps the block pairs').
// A plane or a concave terrain (a valley) has no convex edge, so there the vertex pairs alone act.
// Convex edges are the raster's interior edges across which the two triangles fold down by more
// than a length tolerance. Contacts of one body whose two points both coincide within 4
// tolerances are merged, the first kept (vertex, wall, node, edge). Cost: the core's vertices (each
// against the cells within R of it), and its edges against the raster nodes and edges under its
// box, whatever the raster's size.
//
// Contact keys (SdemGeom kinds and indices, A the body, B the terrain): vertex (Vertex v, Face -1:
// the history follows the vertex across triangles); wall (Vertex v, Face 2 (i ny + j) + t: t 0 the
// triangle (i, j), (i+1, j), (i, j+1) of cell (i, j), 1 the other); node (Face -1: the core as a
// whole, Vertex i ny + j); edge (Edge e, Edge 3 (i ny + j) + d, d 0: (i, j)-(i+1, j), 1: (i, j)-(i, j+1), 2: the
// diagonal (i+1, j)-(i, j+1) of cell (i, j)).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/Terrain.hpp"
#include "sdem/Ig2_SpheroPolyhedron_SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace sdem {

class Ig2_SpheroPolyhedron_Terrain {
 public:
  // The terrain (validated by the caller) and its convex edges.
  void setTerrain(const mpmsdem::TerrainSpec& t);

  // Append the contacts of body P with the terrain to `out`. Returns false (and says in `what`
  // which feature) when the terrain reaches P's core: a core vertex at or below the surface, a
  // crest node in the core, or a convex edge through a convex core. The run must then stop.
  bool go(const PosedSpheroPolyhedron& P, std::vector<SdemGeom>& out, std::string& what) const;

  // Whether the raster edge `dir` (0, 1, 2 as in the keys above) at node (i, j) is convex.
  bool convexEdge(int i, int j, int dir) const { return (convex_[node(i, j)] >> dir) & 1; }
  // Whether node (i, j) is a crest node (an end of a convex edge).
  bool crestNode(int i, int j) const { return crest_[node(i, j)] != 0; }

 private:
  // A triangle whose upward normal is within this cosine of another's continues its slope
  // (about 26 deg, the block pairs' "nearly flat"): walls are the triangles steeper than that.
  static constexpr Real wallCosine = Ig2_SpheroPolyhedron_SpheroPolyhedron::patchCosine;

  int node(int i, int j) const { return i * spec_.ny + j; }
  // The wall contacts of core vertex v at p (the upward normal of the triangle under it: `under`):
  // see the file's comment; emit(kindA, indexA, kindB, indexB, pointA, pointB, normal, d).
  template <typename Emit>
  void wallContacts(int v, const Vec3& p, const Vec3& under, Real R, Emit& emit) const;
  Vec3 nodePoint(int i, int j) const;
  // Ends (a, b) of edge dir at node (i, j), and the third vertices of its two triangles.
  void edgePoints(int i, int j, int dir, Vec3& a, Vec3& b, Vec3& c1, Vec3& c2) const;

  mpmsdem::TerrainSpec spec_;
  std::vector<std::uint8_t> convex_;  // per node, bit d: its edge d is convex
  std::vector<std::uint8_t> crest_;   // per node: an end of a convex edge
};

}  // namespace sdem
}  // namespace mpmsdem
