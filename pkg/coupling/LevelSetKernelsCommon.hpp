// Contact of a material point with a YADE LevelSet body (Ig2_MaterialPoint_LevelSet), written
// once as __host__ __device__ functions over plain arrays like CouplingKernelsCommon.hpp: the
// CPU loop (MpLevelSetCoupling.cpp) calls exactly these, in double or float.
//
// The material point is the sphere of radius R_p0 of Eq 13, as against SDEM blocks. The body is
// its signed distance field phi, sampled on a regular grid in the body's local frame (YADE's
// LevelSet::lsGrid and distField: phi < 0 inside, > 0 outside). Between grid points phi is the
// trilinear interpolant of the eight values of the cell, and the contact normal is the
// normalised gradient of that interpolant (what YADE's LevelSet::distance and ::normal
// evaluate). With d = phi(point), the overlap is delta = R_p0 - d (Eq 12 with R_b = 0: the zero
// level set is the body's surface, there is no sweep sphere) and the barrier reach R = R_p0.
// The law is the block one (sdem::barrierCoulomb: Eq 10 barrier, incremental Coulomb spring),
// and the force is split as for blocks: on the particle into its external-force slot (spread to
// the grid by the next MPM step, Eq 14), the opposite on the body at the contact point.
#pragma once
#include "coupling/CouplingKernelsCommon.hpp"

namespace mpmsdem {
namespace coupling {

// One body's distance grid (a view into host or device arrays).
template <typename T>
struct LevelSetGridView {
  T min[3];       // local position of grid point (0, 0, 0) [m]
  T spacing;      // grid step h [m], > 0
  int nGP[3];     // grid points per axis, >= 2
  const T* dist;  // phi at grid point (i, j, k): dist[(i nGP[1] + j) nGP[2] + k] [m]
};

// phi and its gradient at a point of the body frame. Outside the grid's box, where the grid
// says nothing, phi is continued from the nearest point c of the box as phi(c) + |p - c|: a
// distance changes by at most the distance moved, so this is the largest value phi can have
// there and the continuation never makes a contact the body would not (a linear one can: YADE's
// box grids hold max(|x_i| - a_i) beyond the faces, flat along the side, which a gradient would
// carry out unchanged). It is exact beyond a face parallel to the box's side, as YADE's shapes
// have, whose grids end a cell or so past the surface, short of the barrier's reach R_p0.
// The gradient is that of the continued field: (p - c)_d / |p - c| along the axes p was brought
// back on, the interpolant's along the others.
template <typename T>
struct LevelSetSample {
  T distance;           // phi [m]
  Vec3T<T> gradient;    // grad phi of the interpolant [-] (|grad phi| = 1 for an exact distance)
};

template <typename T>
MPM_HD_INLINE LevelSetSample<T> sampleLevelSet(const LevelSetGridView<T>& g, const Vec3T<T>& p) {
  int c[3];
  T u[3];
  Vec3T<T> outside{T(0), T(0), T(0)};  // p - c [m]
  for (int d = 0; d < 3; ++d) {
    T t = (p[d] - g.min[d]) / g.spacing;
    const T last = T(g.nGP[d] - 1);
    if (t < T(0)) {
      outside[d] = t * g.spacing;
      t = T(0);
    } else if (t > last) {
      outside[d] = (t - last) * g.spacing;
      t = last;
    }
    int i = static_cast<int>(mpmsdem::hdFloor(t));
    if (i > g.nGP[d] - 2) i = g.nGP[d] - 2;  // a point on the last grid plane is in the last cell
    c[d] = i;
    u[d] = t - T(i);
  }
  const int sj = g.nGP[2], si = g.nGP[1] * g.nGP[2];
  const T* v = g.dist + static_cast<long long>(c[0]) * si + static_cast<long long>(c[1]) * sj + c[2];
  // corner (a, b, e) of the cell at v[a si + b sj + e]; weights (1 - u) for 0, u for 1 per axis
  const T v000 = v[0], v001 = v[1], v010 = v[sj], v011 = v[sj + 1];
  const T v100 = v[si], v101 = v[si + 1], v110 = v[si + sj], v111 = v[si + sj + 1];
  const T x = u[0], y = u[1], z = u[2];
  // along z first, then y, then x: each gradient component is a difference across the cell
  const T e00 = v000 + z * (v001 - v000), e01 = v010 + z * (v011 - v010);
  const T e10 = v100 + z * (v101 - v100), e11 = v110 + z * (v111 - v110);
  const T f0 = e00 + y * (e01 - e00), f1 = e10 + y * (e11 - e10);
  const T inv = T(1) / g.spacing;
  LevelSetSample<T> s;
  s.gradient.x = (f1 - f0) * inv;
  s.gradient.y = ((T(1) - x) * (e01 - e00) + x * (e11 - e10)) * inv;
  const T dz00 = v001 - v000, dz01 = v011 - v010, dz10 = v101 - v100, dz11 = v111 - v110;
  s.gradient.z = ((T(1) - x) * ((T(1) - y) * dz00 + y * dz01) + x * ((T(1) - y) * dz10 + y * dz11)) * inv;
  s.distance = f0 + x * (f1 - f0);
  const T o = sdem::norm(outside);
  if (o > T(0)) {
    s.distance += o;
    for (int d = 0; d < 3; ++d)
      if (outside[d] != T(0)) s.gradient[d] = outside[d] / o;
  }
  return s;
}

// Couple the particle in slot p with the level-set bodies B[0 .. nBodies) (their grids in
// grids[B[b].shape], their pair physics in phys[B[b].phys]; BlockState::reach is the radius about
// pos of a sphere holding the grid's box). The rest as coupleParticle (CouplingKernelsCommon.hpp):
// sink(const MpContact<T>&) per contact (featureKind kFeatureFace, featureIndex 0: a level set has
// no faces, edges or vertices to tell apart), the particle's force added into P.force, its history
// slots rewritten when it touches (key: the body index), *approach lowered for pairs that close
// (examined up to `watch` [m] beyond contact). Returns kCoupleOk,
// or kCoupleCoreReached with *badBody set when the particle centre is on or inside the body's
// surface (phi <= 0) or phi has no gradient there: the barrier cannot push it out.
template <typename T, typename Sink>
MPM_HD_INLINE int coupleParticleLevelSets(int p, const CouplingParticles<T>& P, const BlockState<T>* B, int nBodies,
                                          const LevelSetGridView<T>* grids, const sdem::BarrierCoulombPhys<T>* phys,
                                          const HistoryView<T>& H, T dt, T safety, T watch, Sink& sink, int* badBody,
                                          int* overflow, T* approach, CouplingLoopMemo<T>& memo) {
  const Vec3T<T> x{P.x[0][p], P.x[1][p], P.x[2][p]};
  ParticleContacts<T> pc(H, particleNumber(P, p));
  const T rp = particleRadius(P.vol0[p], memo);
  const T mp = P.mass[p];
  const Vec3T<T> vp{P.v[0][p], P.v[1][p], P.v[2][p]};
  for (int b = 0; b < nBodies; ++b) {
    const BlockState<T>& blk = B[b];
    const Vec3T<T> r{x.x - blk.pos[0], x.y - blk.pos[1], x.z - blk.pos[2]};
    const T reach = blk.reach + rp;
    if (mpmsdem::dot(r, r) >= (reach + watch) * (reach + watch)) continue;
    const T* R = blk.rot;
    const Vec3T<T> xb{R[0] * r.x + R[3] * r.y + R[6] * r.z, R[1] * r.x + R[4] * r.y + R[7] * r.z,
                      R[2] * r.x + R[5] * r.y + R[8] * r.z};
    const LevelSetSample<T> s = sampleLevelSet(grids[blk.shape], xb);
    const T cutoff = rp;
    const T closing = closingDistance(vp, blk, reach, T(kFirstContactHorizon) * dt, watch);
    if (s.distance >= cutoff + closing) continue;
    const T gnorm = sdem::norm(s.gradient);
    if (!(s.distance > T(0)) || !(gnorm > T(0))) {  // also NaN
      *badBody = b;
      return kCoupleCoreReached;
    }
    const Vec3T<T> nb = (T(1) / gnorm) * s.gradient;
    const Vec3T<T> n{R[0] * nb.x + R[1] * nb.y + R[2] * nb.z, R[3] * nb.x + R[4] * nb.y + R[5] * nb.z,
                     R[6] * nb.x + R[7] * nb.y + R[8] * nb.z};
    // midway between the body's surface (d along -n) and the particle sphere's surface
    const Vec3T<T> c = x - (T(0.5) * (s.distance + rp)) * n;
    const Vec3T<T> rc{c.x - blk.pos[0], c.y - blk.pos[1], c.z - blk.pos[2]};
    const Vec3T<T> w{blk.angVel[0], blk.angVel[1], blk.angVel[2]};
    const Vec3T<T> vb = Vec3T<T>{blk.vel[0], blk.vel[1], blk.vel[2]} + sdem::cross(w, rc);
    if (s.distance >= cutoff) {  // not touching yet
      lowerApproachBound(s.distance - cutoff, vp, vb, n, dt, mp, cutoff, phys[blk.phys], safety, approach);
      continue;
    }
    actOnContact(pc, static_cast<long long>(b) << 32, b, sdem::kFeatureFace, 0, blk, phys[blk.phys], cutoff,
                 s.distance, n, c, vp, vb, mp, dt, overflow, sink);
  }
  pc.finish(P, p);
  return kCoupleOk;
}

}  // namespace coupling
}  // namespace mpmsdem
