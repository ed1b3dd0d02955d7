// The surface of a level-set body for the ParaView records: the zero level set of its grid as a
// closed triangle mesh in the body's local frame. Marching tetrahedra: each grid cell is split
// into the six tetrahedra around its main diagonal (the Freudenthal split, the same in every
// cell, so neighbouring cells cut their shared faces alike and the mesh has no cracks), and the
// surface gets a vertex on each grid or diagonal edge it crosses, where the linear interpolation
// of phi along that edge is zero; the triangles through an edge share its vertex. What the flow
// meets is the trilinear interpolation of the same grid (LevelSetKernelsCommon.hpp): the two
// agree on the cell edges and differ inside a cell, so this mesh is a picture of the body, not
// its contact surface.
#pragma once
#include "coupling/MpLevelSetCoupling.hpp"
#include "io/VtkWriter.hpp"

namespace mpmsdem {
namespace coupling {

// The zero level set of `grid` (local frame [m]), each triangle wound so that its normal points
// out of the body (towards phi > 0); id: the body id it carries. A node with phi exactly 0
// counts as outside. Empty when phi has one sign on the whole grid.
io::RigidSurface levelSetSurface(const LevelSetGrid& grid, int id);

// `local` placed in the world: x = pos + R x_local (R: local -> world).
io::RigidSurface placedSurface(const io::RigidSurface& local, const Vec3& pos, const Mat3& R);

}  // namespace coupling
}  // namespace mpmsdem
