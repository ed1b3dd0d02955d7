// MP–SDEM contact of one material point (paper §2.3, Eqs 12–16) written once as a
// __host__ __device__ function: the CPU loop (MpSdemCoupling.cpp) and the CUDA kernel
// (cuda/MpSdemCouplingKernels.cuh) call exactly this, in double or float.
//
// A material point is a sphere of radius R_p0 = (3 V0 / (4 pi))^(1/3) (Eq 13 with
// V0 = dx^3 / n_i). Against block b its overlap is delta = R_p0 + R_b - d(MP, core) (Eq 12),
// with the block–block laws (barrier normal force, incremental Coulomb tangential spring).
// The force on the particle goes into its external-force slot, which the next MPM step
// spreads to the grid with the P2G weights (Eq 14); the opposite force acts on the block at
// the contact point.
#pragma once
#include <cstdint>

#include "sdem/SdemKernelsCommon.hpp"

namespace mpmsdem {
namespace coupling {

using mpmsdem::Vec3T;

// Pose and motion of one block for this step (world frame).
template <typename T>
struct BlockState {
  T pos[3];      // centroid [m]
  T rot[9];      // rotation body -> world, row-major
  T vel[3];      // [m/s]
  T angVel[3];   // [rad/s]
  T mass;        // [kg]
  T reach;       // bounding radius of the rounded body [m]
  int shape;     // index in the shape table
  int phys;      // index in the pair-physics table
  int fixed;     // 1: the block does not respond to forces (meff = particle mass)
};

// The host keeps blocks and pair physics in double; a float step (CPU or CUDA) reads them
// rounded once per step by these.
template <typename T>
BlockState<T> convertBlock(const BlockState<double>& a) {
  BlockState<T> b;
  for (int d = 0; d < 3; ++d) {
    b.pos[d] = static_cast<T>(a.pos[d]);
    b.vel[d] = static_cast<T>(a.vel[d]);
    b.angVel[d] = static_cast<T>(a.angVel[d]);
  }
  for (int k = 0; k < 9; ++k) b.rot[k] = static_cast<T>(a.rot[k]);
  b.mass = static_cast<T>(a.mass);
  b.reach = static_cast<T>(a.reach);
  b.shape = a.shape;
  b.phys = a.phys;
  b.fixed = a.fixed;
  return b;
}

template <typename T>
sdem::BarrierCoulombPhys<T> convertPhys(const sdem::BarrierCoulombPhys<double>& p) {
  return {static_cast<T>(p.kc), static_cast<T>(p.mu), static_cast<T>(p.nu), static_cast<T>(p.zetaN),
          static_cast<T>(p.zetaT)};
}

// Uniform bins over the MPM grid box listing the blocks whose rounded-body box, grown by the
// largest particle radius and by `watch`, touches them. The bins some block's box reaches are
// few against the grid's (a village's blocks in a valley): each bin holds a slot, -1 for none,
// and the blocks of slot s are blocks[first[s] .. first[s + 1]), in ascending order; so a table
// that changes costs its slots, not the grid.
struct BinGridView {
  double origin[3];   // lower corner [m]
  double invSize;     // 1 / bin edge [1/m]
  int dims[3];        // bins per axis
  const int* slot;    // per bin (dims[0] dims[1] dims[2]): its slot, or -1
  const int* first;   // per slot + 1: offsets into blocks
  const int* blocks;  // block indices
  double watch;       // how far beyond the largest particle radius the block boxes were grown [m]
};

// The bin of a point at (x, y, z) [m]; points outside the bins take the nearest.
MPM_HD_INLINE int binOf(const BinGridView& bins, double x, double y, double z) {
  const double p[3] = {x, y, z};
  int bc[3];
  for (int d = 0; d < 3; ++d) {
    const int c = static_cast<int>(mpmsdem::hdFloor((p[d] - bins.origin[d]) * bins.invSize));
    bc[d] = c < 0 ? 0 : (c >= bins.dims[d] ? bins.dims[d] - 1 : c);
  }
  return (bc[0] * bins.dims[1] + bc[1]) * bins.dims[2] + bc[2];
}

// Stable-step bound for the step after this one, from a particle that does not touch a block
// yet but closes on it [s]: gap g = d - R_p0 - R_b > 0 at normal speed vn > 0, R = R_p0 + R_b
// the barrier's reach. The next step's forces come from the contacts at its start, which the
// automatic step does not know when it chooses the step: it sees the contacts of this step,
// and a point that first touches at the end of this step may then start the next one deep in
// a stiff barrier (k_c 1e7 N/m: the step exceeded twice its contact step). This step (dt)
// brings the point to delta = vn dt - g; near first touch the barrier's tangent stiffness is
// k_n = 6 k_c delta / R to leading order (Eq 10 expanded) and K_t = k_n / (2 (1 + nu)), so the
// next step is within the point's contact step when it is at most
// safety sqrt(m R / (6 k_c delta max(1, 1 / (2 (1 + nu))))); +inf when the point does not
// reach the barrier within dt.
template <typename T>
MPM_HD_INLINE T barrierStiffnessFactor(const sdem::BarrierCoulombPhys<T>& phys) {
  // max(1, K_t / k_n): the stiffer of the normal barrier and the tangential spring sets the step
  const T tangential = T(1) / (T(2) * (T(1) + phys.nu));
  return tangential > T(1) ? tangential : T(1);
}

template <typename T>
MPM_HD_INLINE T approachStepBound(T gap, T vn, T dt, T mass, T reach, const sdem::BarrierCoulombPhys<T>& phys,
                                  T safety) {
  const T delta = vn * dt - gap;
  if (!(delta > T(0))) return T(INFINITY);
  return safety * mpmsdem::hdSqrt(mass * reach / (T(6) * phys.kc * delta * barrierStiffnessFactor(phys)));
}

// Stable-step bound for a particle closing at normal speed vn > 0 on a barrier it has not
// reached yet, whenever it arrives [s]: a step dt that lets it arrive ends with it at most
// delta = vn dt inside, where k_n = 6 k_c delta / R (as above), so dt is stable there while
// dt <= safety sqrt(m R / (6 k_c vn dt kappa)), i.e. dt <= (safety^2 m R / (6 k_c vn kappa))^(1/3)
// with kappa = max(1, 1 / (2 (1 + nu))). approachStepBound only sees the points that arrive
// within the current step, so with a stiff barrier (k_c 1e9 N/m) the step that brings a point
// in could already be far too long (measured: the flow's kinetic energy grew tenfold at first
// contact); this bound, taken by the points that may arrive during the next step, shortens that
// step before it. With the paper's
// k_c 1e4 N/m it lies above the CFL step of the paper's scenes (0.25 ms at dx 0.01 m, 1 m/s).
template <typename T>
MPM_HD_INLINE T firstContactStepBound(T vn, T mass, T reach, const sdem::BarrierCoulombPhys<T>& phys, T safety) {
  return mpmsdem::hdCbrt(safety * safety * mass * reach / (T(6) * phys.kc * vn * barrierStiffnessFactor(phys)));
}

// How many of the current step a non-touching pair is examined over: this step and the next,
// which the automatic step lets grow by at most 1 % (sdem::kAutoStepGrowth).
constexpr double kFirstContactHorizon = 2.01;

// An upper bound of how far a particle at velocity vp and a block close on each other within
// dt [m]: dt (|vp - v_b|_1 + |w_b|_1 reach), reach the block's bounding radius plus the particle
// radius; at most `limit` (NaN too). The 1-norms bound the speeds at no more than sqrt(3)
// above without a root: this runs for every pair near a block.
template <typename T>
MPM_HD_INLINE T closingDistance(const Vec3T<T>& vp, const BlockState<T>& blk, T reach, T dt, T limit) {
  const T v = mpmsdem::hdAbs(vp.x - blk.vel[0]) + mpmsdem::hdAbs(vp.y - blk.vel[1]) + mpmsdem::hdAbs(vp.z - blk.vel[2]);
  const T w = mpmsdem::hdAbs(blk.angVel[0]) + mpmsdem::hdAbs(blk.angVel[1]) + mpmsdem::hdAbs(blk.angVel[2]);
  const T d = dt * (v + w * reach);
  return d <= limit ? d : limit;
}

// Tangential history of a particle's contacts: `slots` entries per particle, each a key
// (block << 32 | feature kind << 28 | feature index, or -1 when empty) and xi, the elastic
// tangential force F_el [N] of sdem::barrierCoulomb (not a displacement). Indexed
// by particle id, so it follows the particle as long as particles keep their ids.
// A particle's slots hold its contacts of the previous step only when that step wrote them
// (written[id] == step - 1); otherwise they are empty. So a particle without contact writes
// nothing: most points of a flow never touch a block, and clearing their slots every step was
// a scattered read and write by particle number for each of them.
template <typename T>
struct HistoryView {
  long long* key;      // slots per particle
  T* xi;               // 3 x slots per particle
  unsigned* written;   // per particle: the step that last wrote its slots
  unsigned step;       // this step's number (wraps; only equality with step - 1 is used)
  int slots;
};

// Whether particle h's history slots hold the previous step's contacts.
template <typename T>
MPM_HD_INLINE bool historyCurrent(const HistoryView<T>& H, int h) {
  return H.written[h] == H.step - 1u;
}

// One MP–block contact, handed to the caller's sink.
template <typename T>
struct MpContact {
  int particle, block, featureKind, featureIndex;  // particle: its number (CouplingParticles::id)
  Vec3T<T> force;     // on the particle [N] (the block takes -force at `point`)
  Vec3T<T> point;     // contact point, midway between the two sphere surfaces [m]
  Vec3T<T> normal;    // unit, from the block towards the particle
  T overlap;          // delta [m]
  T particleMass;     // [kg]
  sdem::BarrierCoulombResult<T> law;  // forces, stiffnesses, energies of the law
};


// Status of one particle's coupling.
constexpr int kCoupleOk = 0;
constexpr int kCoupleCoreReached = 1;  // the particle centre reached a block core (delta >= R)

// The solver's particles (mpm::ParticleView): x, v, mass, vol0 and force per storage slot; the
// histories per particle number id[slot] (id null: slot and number are the same).
template <typename T>
struct CouplingParticles {
  const T* x[3];
  const T* v[3];
  const T* mass;
  const T* vol0;
  T* force[3];  // accumulate-into external force of the next MPM step [N]
  const int* id;
};

template <typename T>
MPM_HD_INLINE int particleNumber(const CouplingParticles<T>& P, int p) {
  return P.id ? P.id[p] : p;
}

// What one particle leaves for the next in a caller's loop over neighbouring particles. The
// radius R_p0 of the last initial volume met: points seeded together share V0, so the loop takes
// one cube root instead of one per point (the root was a third of the coupling's time on the
// CPU). The face plane that last put a point out of a block's reach: the next point near the
// same block (the bed under a flow) is most often culled by the same plane, with one dot product
// instead of one per face. Both give exactly what they replace.
template <typename T>
struct CouplingLoopMemo {
  T volume = T(-1);
  T radius = T(0);
  int cullBlock = -1;
  int cullFace = -1;
};

template <typename T>
MPM_HD_INLINE T particleRadius(T volume0, CouplingLoopMemo<T>& memo) {
  if (!(volume0 == memo.volume)) {
    memo.volume = volume0;
    memo.radius = mpmsdem::hdCbrt(T(3) * volume0 / T(4 * 3.14159265358979323846));
  }
  return memo.radius;
}

// One particle's contacts within a step, as the SDEM-block loop (coupleParticle) and the level-set
// loop (coupleParticleLevelSets) keep them alike: its history slots, read at its first contact
// (most points near a block touch nothing) and rewritten contact by contact, and the sum of the
// forces on it.
template <typename T>
struct ParticleContacts {
  static constexpr int kMaxSlots = 4;
  HistoryView<T> H;
  int h;             // the particle's number (CouplingParticles::id)
  long long slot0;   // its first history slot; 64-bit, as 3 x slots x number passes 2^31 at a few 10^8 points
  int slots;
  bool oldRead = false;
  int used = 0;
  long long oldKey[kMaxSlots];
  T oldXi[3 * kMaxSlots];
  Vec3T<T> fsum{T(0), T(0), T(0)};

  MPM_HD_INLINE ParticleContacts(const HistoryView<T>& history, int number)
      : H(history), h(number), slot0(static_cast<long long>(history.slots) * number),
        slots(history.slots < kMaxSlots ? history.slots : kMaxSlots) {}

  // The elastic tangential force the pair `key` carried at the end of the previous step (zero
  // for a pair that was not in contact then).
  MPM_HD_INLINE void previous(long long key, T xi[3]) {
    if (!oldRead) {
      const bool current = historyCurrent(H, h);
      for (int k = 0; k < slots; ++k) {
        oldKey[k] = current ? H.key[slot0 + k] : -1;
        if (oldKey[k] >= 0)
          for (int d = 0; d < 3; ++d) oldXi[3 * k + d] = H.xi[3 * (slot0 + k) + d];
      }
      oldRead = true;
    }
    for (int d = 0; d < 3; ++d) xi[d] = T(0);
    for (int k = 0; k < slots; ++k)
      if (oldKey[k] == key)
        for (int d = 0; d < 3; ++d) xi[d] = oldXi[3 * k + d];
  }

  // Keep this step's xi of the pair `key` for the next step; *overflow counts the pairs that
  // found no free slot (their tangential force is not carried over).
  MPM_HD_INLINE void keep(long long key, const T xi[3], int* overflow) {
    if (used < slots) {
      H.key[slot0 + used] = key;
      for (int d = 0; d < 3; ++d) H.xi[3 * (slot0 + used) + d] = xi[d];
      ++used;
    } else {
      ++*overflow;
    }
  }

  // After the particle's last pair: the slots of contacts that ended are emptied and the step
  // marked (without contact the slots go stale unwritten: HistoryView), and the forces added to
  // the particle in slot p.
  MPM_HD_INLINE void finish(const CouplingParticles<T>& P, int p) {
    if (used > 0) {
      for (int k = used; k < slots; ++k) H.key[slot0 + k] = -1;
      H.written[h] = H.step;
    }
    for (int d = 0; d < 3; ++d) P.force[d][p] += fsum[d];
  }
};

// A pair not yet in contact, `gap` [m] apart along the unit normal n (from the block towards the
// particle), closing if the particle's velocity vp relative to the block's surface velocity vb has
// a component against n: *approach is lowered to the smaller of approachStepBound and
// firstContactStepBound (the particle's mass mp, the pair's barrier `cutoff` and physics).
template <typename T>
MPM_HD_INLINE void lowerApproachBound(T gap, const Vec3T<T>& vp, const Vec3T<T>& vb, const Vec3T<T>& n, T dt, T mp,
                                      T cutoff, const sdem::BarrierCoulombPhys<T>& phys, T safety, T* approach) {
  const T vn = -mpmsdem::dot(vp - vb, n);
  if (vn > T(0)) {
    const T arriving = approachStepBound(gap, vn, dt, mp, cutoff, phys, safety);
    const T first = firstContactStepBound(vn, mp, cutoff, phys, safety);
    const T bound = arriving < first ? arriving : first;
    if (bound < *approach) *approach = bound;
  }
}

// A pair in contact: overlap delta = cutoff - distance along the unit normal n at the point c, the
// particle's velocity vp against the block's surface velocity vb there. The barrier and Coulomb
// laws with the pair's tangential history (key), the contact handed to sink and its force added
// to the particle's sum.
template <typename T, typename Sink>
MPM_HD_INLINE void actOnContact(ParticleContacts<T>& pc, long long key, int block, int featureKind, int featureIndex,
                                const BlockState<T>& blk, const sdem::BarrierCoulombPhys<T>& phys, T cutoff,
                                T distance, const Vec3T<T>& n, const Vec3T<T>& c, const Vec3T<T>& vp,
                                const Vec3T<T>& vb, T mp, T dt, int* overflow, Sink& sink) {
  const T delta = cutoff - distance;
  const T meff = blk.fixed ? mp : mp * blk.mass / (mp + blk.mass);
  T xi[3];
  pc.previous(key, xi);
  MpContact<T> ct;
  ct.law = sdem::barrierCoulomb(phys, cutoff, delta, n, vp - vb, meff, dt, xi);
  pc.keep(key, xi, overflow);
  ct.particle = pc.h;
  ct.block = block;
  ct.featureKind = featureKind;
  ct.featureIndex = featureIndex;
  ct.force = ct.law.normalForce * n + ct.law.tangential;
  ct.point = c;
  ct.normal = n;
  ct.overlap = delta;
  ct.particleMass = mp;
  pc.fsum = pc.fsum + ct.force;
  sink(ct);
}

// Couple the particle in slot p with the blocks listed in its bin. Calls sink(const MpContact<T>&)
// for each contact, adds the particle's forces into P.force, rewrites its history slots if it
// touches a block, and lowers *approach to the approachStepBound of each block it reaches within
// dt without touching it now and to the firstContactStepBound of each block it closes on (with
// the SDEM time-step safety `safety`; pairs further apart than
// bins.watch are not examined). Returns kCoupleOk, or kCoupleCoreReached with *badBlock set (the
// step is then invalid: the barrier cannot act once the centre is at the core, which means the
// time step was too large or the particle started inside the block). `overflow` counts contacts that found no free history
// slot (they act without tangential memory this step); `memo` is the caller's, kept across the
// particles of its loop.
template <typename T, typename Sink>
MPM_HD_INLINE int coupleParticle(int p, const CouplingParticles<T>& P, const BlockState<T>* B,
                                 const sdem::ShapeTableView<T>& S, const sdem::BarrierCoulombPhys<T>* phys,
                                 const BinGridView& bins, const HistoryView<T>& H, T dt, T safety, Sink& sink,
                                 int* badBlock, int* overflow, T* approach, CouplingLoopMemo<T>& memo) {
  const Vec3T<T> x{P.x[0][p], P.x[1][p], P.x[2][p]};
  const int bin = binOf(bins, x[0], x[1], x[2]);
  const int s = bins.slot[bin];
  if (s < 0) return kCoupleOk;  // no block near; its history goes stale (HistoryView)
  const int b0 = bins.first[s], b1 = bins.first[s + 1];
  ParticleContacts<T> pc(H, particleNumber(P, p));
  const T rp = particleRadius(P.vol0[p], memo);
  const T mp = P.mass[p];
  const Vec3T<T> vp{P.v[0][p], P.v[1][p], P.v[2][p]};
  for (int i = b0; i < b1; ++i) {
    const int b = bins.blocks[i];
    const BlockState<T>& blk = B[b];
    const Vec3T<T> r{x.x - blk.pos[0], x.y - blk.pos[1], x.z - blk.pos[2]};
    const Vec3T<T> w{blk.angVel[0], blk.angVel[1], blk.angVel[2]};
    const T reach = blk.reach + rp;
    if (mpmsdem::dot(r, r) >= (reach + T(bins.watch)) * (reach + T(bins.watch))) continue;
    const T* R = blk.rot;
    const Vec3T<T> xb{R[0] * r.x + R[3] * r.y + R[6] * r.z, R[1] * r.x + R[4] * r.y + R[7] * r.z,
                      R[2] * r.x + R[5] * r.y + R[8] * r.z};
    const T cutoff = S.sweepRadius[blk.shape] + rp;
    // A pair that does not touch is examined only as far as it can close within this step and
    // the next (closing; the next is at most kFirstContactHorizon - 1 times this one): a point
    // that arrives during the next step is then seen now, and firstContactStepBound shortens that
    // step before it brings the point into a stiff barrier.
    const T closing = closingDistance(vp, blk, reach, T(kFirstContactHorizon) * dt, T(bins.watch));
    if (memo.cullBlock == b && sdem::facePlaneDistance(S, memo.cullFace, xb) >= cutoff + closing) continue;
    int face;
    const T lower = sdem::coreDistanceLowerBound(S, blk.shape, xb, &face);
    if (lower >= cutoff + closing) {
      memo.cullBlock = b;
      memo.cullFace = face;
      continue;
    }
    const sdem::CoreQuery<T> q = sdem::closestPointOnCore(S, blk.shape, xb);
    const T watch = q.distance >= cutoff ? closing : T(bins.watch);
    if (q.distance >= cutoff + watch) continue;
    if (!(q.distance > T(0))) {  // also NaN
      *badBlock = b;
      return kCoupleCoreReached;
    }
    const Vec3T<T> nb = (T(1) / q.distance) * (xb - q.closest);
    const Vec3T<T> n{R[0] * nb.x + R[1] * nb.y + R[2] * nb.z, R[3] * nb.x + R[4] * nb.y + R[5] * nb.z,
                     R[6] * nb.x + R[7] * nb.y + R[8] * nb.z};
    const Vec3T<T> cw = x - q.distance * n;  // closest core point, world frame
    const T Rb = S.sweepRadius[blk.shape];
    const Vec3T<T> c = T(0.5) * ((cw + Rb * n) + (x - rp * n));
    const Vec3T<T> rc{c.x - blk.pos[0], c.y - blk.pos[1], c.z - blk.pos[2]};
    const Vec3T<T> vb = Vec3T<T>{blk.vel[0], blk.vel[1], blk.vel[2]} + sdem::cross(w, rc);
    if (q.distance >= cutoff) {  // not touching yet
      lowerApproachBound(q.distance - cutoff, vp, vb, n, dt, mp, cutoff, phys[blk.phys], safety, approach);
      continue;
    }
    const long long key = (static_cast<long long>(b) << 32) | (static_cast<long long>(q.featureKind) << 28) |
                          static_cast<long long>(q.featureIndex);
    actOnContact(pc, key, b, q.featureKind, q.featureIndex, blk, phys[blk.phys], cutoff, q.distance, n, c, vp, vb, mp,
                 dt, overflow, sink);
  }
  pc.finish(P, p);
  return kCoupleOk;
}

// Per-block sums of one step, kBlockSums doubles per block: what the flow does to the block.
constexpr int kSumForce = 0;      // 3: force on the block [N]
constexpr int kSumTorque = 3;     // 3: torque about its centroid [N m]
constexpr int kSumFace = 6;       // 3: force from contacts on face interiors (F_f, paper §3.2.3) [N]
constexpr int kSumEdge = 9;       // 3: force from contacts on edges and vertices (F_e) [N]
constexpr int kSumK = 12;         // sum of max(k_n, K_t) [N/m] (critical step)
constexpr int kSumKr = 13;        // sum of k_n |r x n|^2 + K_t |r|^2 [N m] (critical step, rotation)
constexpr int kSumCount = 14;     // number of MP contacts
constexpr int kSumBarrier = 15;   // barrier energy [J]
constexpr int kSumSpring = 16;    // tangential spring energy [J]
constexpr int kSumFriction = 17;  // slip work of this step [J]
constexpr int kSumDamping = 18;   // dashpot work of this step [J]
constexpr int kBlockSums = 19;

// Contact c's share of its block's sums (kBlockSums values; the sums are added up in double).
template <typename T>
MPM_HD_INLINE void blockShare(const MpContact<T>& c, const BlockState<T>& b, double share[kBlockSums]) {
  const Vec3T<T> rc{c.point.x - b.pos[0], c.point.y - b.pos[1], c.point.z - b.pos[2]};
  const Vec3T<T> f{-c.force.x, -c.force.y, -c.force.z};
  const Vec3T<T> tq = sdem::cross(rc, f);
  const int split = c.featureKind == sdem::kFeatureFace ? kSumFace : kSumEdge;
  const int other = split == kSumFace ? kSumEdge : kSumFace;
  for (int d = 0; d < 3; ++d) {
    share[kSumForce + d] = static_cast<double>(f[d]);
    share[kSumTorque + d] = static_cast<double>(tq[d]);
    share[split + d] = static_cast<double>(f[d]);
    share[other + d] = 0.0;
  }
  const Vec3T<T> rn = sdem::cross(rc, c.normal);
  share[kSumK] = static_cast<double>(c.law.kn > c.law.kt ? c.law.kn : c.law.kt);
  share[kSumKr] = static_cast<double>(c.law.kn * mpmsdem::dot(rn, rn) + c.law.kt * mpmsdem::dot(rc, rc));
  share[kSumCount] = 1.0;
  share[kSumBarrier] = static_cast<double>(c.law.barrierEnergy);
  share[kSumSpring] = static_cast<double>(c.law.springEnergy);
  share[kSumFriction] = static_cast<double>(c.law.frictionWork);
  share[kSumDamping] = static_cast<double>(c.law.dampingWork);
}

// Add contact c's share to its block's sums with add(double* slot, double value) (a plain +=
// on the CPU, an atomic add on the GPU); the F_f/F_e sum the contact is not part of is left alone.
template <typename T, typename Add>
MPM_HD_INLINE void addBlockShare(const MpContact<T>& c, const BlockState<T>& b, double* sums, const Add& add) {
  double share[kBlockSums];
  blockShare(c, b, share);
  double* s = sums + kBlockSums * c.block;
  const int other = c.featureKind == sdem::kFeatureFace ? kSumEdge : kSumFace;
  for (int k = 0; k < kBlockSums; ++k)
    if (k < other || k >= other + 3) add(s + k, share[k]);
}

// A contact as MpSdemCoupling::contacts() hands it out, kContactValues doubles: the CPU loop
// and the CUDA contact list write the same values.
constexpr int kRecPoint = 0;        // 3: contact point [m]
constexpr int kRecNormal = 3;       // 3: unit normal, from the block towards the point
constexpr int kRecForce = 6;        // 3: force on the block [N]
constexpr int kRecNormalForce = 9;  // F_n [N]
constexpr int kRecOverlap = 10;     // delta [m]
constexpr int kRecFeature = 11;     // the block core's feature kind (sdem::kFeature*)
constexpr int kRecParticle = 12;    // the particle's number
constexpr int kRecBlock = 13;       // the block's index
constexpr int kRecOrder = 14;       // the contact's place among its particle's (device list only)
constexpr int kContactValues = 15;

template <typename T>
MPM_HD_INLINE void contactRecord(const MpContact<T>& c, double r[kContactValues]) {
  for (int d = 0; d < 3; ++d) {
    r[kRecPoint + d] = static_cast<double>(c.point[d]);
    r[kRecNormal + d] = static_cast<double>(c.normal[d]);
    r[kRecForce + d] = -static_cast<double>(c.force[d]);
  }
  r[kRecNormalForce] = static_cast<double>(c.law.normalForce);
  r[kRecOverlap] = static_cast<double>(c.overlap);
  r[kRecFeature] = c.featureKind;
  r[kRecParticle] = c.particle;
  r[kRecBlock] = c.block;
  r[kRecOrder] = 0;
}

// Stable-step bound of the particle side of a contact: sqrt(m_p / max(k_n, K_t)) [s].
template <typename T>
MPM_HD_INLINE T particleStepBound(const MpContact<T>& c) {
  const T k = c.law.kn > c.law.kt ? c.law.kn : c.law.kt;
  return mpmsdem::hdSqrt(c.particleMass / k);
}

}  // namespace coupling
}  // namespace mpmsdem
