#include "mpm/Seeding.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <unordered_map>

#include "common/Error.hpp"
#include "mpm/GridBoundary.hpp"

namespace mpmsdem {
namespace mpm {

namespace {

void checkPerAxis(const std::array<int, 3>& perAxis) {
  const char* axis[3] = {"x", "y", "z"};
  for (int d = 0; d < 3; ++d)
    if (perAxis[d] < 1 || perAxis[d] > 8) throwParameter(std::string("perAxis[") + axis[d] + "]", perAxis[d], "", "in [1, 8]");
}

// Coordinate of the sub-cell centre `sub` of cell `cell` on axis d (the expression seedBox uses).
inline double subCentre(const MpmParams& prm, int d, int cell, int sub, int perAxis) {
  return prm.origin[d] + (cell + (sub + 0.5) / perAxis) * prm.dx;
}

bool degenerate(const std::array<int, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

std::string meshLabel(const std::string& name) { return "mesh '" + name + "'"; }

}  // namespace

double windingNumber(const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& T, const Vec3& p) {
  double sum = 0;
  for (const auto& t : T) {
    if (degenerate(t)) continue;
    const Vec3 a = V[t[0]] - p, b = V[t[1]] - p, c = V[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    // Solid angle of the triangle seen from p: tan(Omega / 2) = det[a b c] / denominator.
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * M_PI);
}

MeshBounds checkSeedMesh(const MpmParams& prm, const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& T,
                         const std::string& name) {
  const std::string label = meshLabel(name);
  if (T.empty()) throwParameter(label + " triangle count", 0, "", "> 0");
  const long nv = static_cast<long>(V.size());
  MeshBounds mb;
  mb.lo = {INFINITY, INFINITY, INFINITY};
  mb.hi = {-INFINITY, -INFINITY, -INFINITY};
  // Undirected edge (lo index, hi index) -> number of triangles using it and the sum of the
  // directions (+1 for lo -> hi, -1 for hi -> lo): a closed, consistently oriented surface has 2 and 0.
  struct EdgeUse {
    int count = 0, direction = 0;
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(3 * T.size());
  std::size_t used = 0;
  for (std::size_t f = 0; f < T.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      if (T[f][c] < 0 || T[f][c] >= nv) {
        std::ostringstream range;
        range << "in [0, " << nv - 1 << "] (a vertex of the mesh)";
        throwParameter(label + " triangle " + std::to_string(f) + " vertex index", T[f][c], "", range.str());
      }
      const Vec3& x = V[T[f][c]];
      if (!x.allFinite())
        throwParameter(label + " vertex " + std::to_string(T[f][c]) + " coordinate", x.transpose(), "m", "finite");
    }
    if (degenerate(T[f])) continue;
    ++used;
    for (int c = 0; c < 3; ++c) {
      const int a = T[f][c], b = T[f][(c + 1) % 3];
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
      EdgeUse& e = edges[key];
      ++e.count;
      e.direction += a < b ? 1 : -1;
    }
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) {
        mb.lo[d] = std::min(mb.lo[d], V[T[f][c]][d]);
        mb.hi[d] = std::max(mb.hi[d], V[T[f][c]][d]);
      }
  }
  if (used == 0) throwParameter(label + " count of triangles with 3 distinct vertices", 0, "", "> 0");
  std::size_t open = 0, misoriented = 0;
  std::uint64_t openKey = 0, misKey = 0;
  int openCount = 0;
  for (const auto& kv : edges) {
    if (kv.second.count != 2) {
      if (open++ == 0 || kv.first < openKey) {
        openKey = kv.first;
        openCount = kv.second.count;
      }
    } else if (kv.second.direction != 0) {
      if (misoriented++ == 0 || kv.first < misKey) misKey = kv.first;
    }
  }
  auto edgeName = [&](std::uint64_t key) {
    return label + " edge (" + std::to_string(key >> 32) + ", " + std::to_string(key & 0xffffffffu) + ")";
  };
  if (open > 0) {
    std::ostringstream range;
    range << "2 (a closed, watertight surface: every edge shared by exactly 2 triangles); " << open
          << " edge(s) are not";
    throwParameter(edgeName(openKey) + " triangle count", openCount, "", range.str());
  }
  if (misoriented > 0) {
    std::ostringstream range;
    range << "opposite in its 2 triangles (a consistently oriented surface); " << misoriented << " edge(s) are not";
    throwParameter(edgeName(misKey) + " direction", "the same in both triangles", "", range.str());
  }
  // Enclosed volume by the divergence theorem, about the box centre for accuracy.
  const Vec3 centre(0.5 * (mb.lo[0] + mb.hi[0]), 0.5 * (mb.lo[1] + mb.hi[1]), 0.5 * (mb.lo[2] + mb.hi[2]));
  double six = 0;
  for (const auto& t : T) {
    if (degenerate(t)) continue;
    six += (V[t[0]] - centre).dot((V[t[1]] - centre).cross(V[t[2]] - centre));
  }
  mb.volume = six / 6.0;
  const double diag =
      std::sqrt((mb.hi[0] - mb.lo[0]) * (mb.hi[0] - mb.lo[0]) + (mb.hi[1] - mb.lo[1]) * (mb.hi[1] - mb.lo[1]) +
                (mb.hi[2] - mb.lo[2]) * (mb.hi[2] - mb.lo[2]));
  if (!(std::fabs(mb.volume) > 1e-9 * diag * diag * diag)) {
    std::ostringstream range;
    range << "> 0 (a closed surface enclosing material; bounding-box diagonal " << diag << " m)";
    throwParameter(label + " enclosed volume", std::fabs(mb.volume), "m^3", range.str());
  }
  const double tol = 1e-9 * prm.dx;
  for (int d = 0; d < 3; ++d) {
    const double a = prm.origin[d] + kWallLayer * prm.dx, b = prm.origin[d] + (prm.cells[d] - kWallLayer) * prm.dx;
    if (mb.lo[d] < a - tol || mb.hi[d] > b + tol) {
      static const char axis[3] = {'x', 'y', 'z'};
      std::ostringstream value, range;
      value << "[" << mb.lo[d] << ", " << mb.hi[d] << "]";
      range << "inside the material region [" << a << ", " << b << "] m on " << axis[d] << " (the grid box less its "
            << kWallLayer << "-cell wall layers)";
      throwParameter(label + " bounding box on " + axis[d], value.str(), "m", range.str());
    }
  }
  return mb;
}

std::size_t seedMesh(const MpmParams& prm, const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& T,
                     const std::array<int, 3>& perAxis, const std::array<double, 3>& velocity, SeedSink& out,
                     const std::string& name) {
  checkPerAxis(perAxis);
  const MeshBounds mb = checkSeedMesh(prm, V, T, name);
  const double sign = mb.volume > 0 ? 1.0 : -1.0;  // winding number inside: +1 or -1
  double diag2 = 0;
  for (int d = 0; d < 3; ++d) diag2 += (mb.hi[d] - mb.lo[d]) * (mb.hi[d] - mb.lo[d]);
  const double epsL = 1e-9 * std::sqrt(diag2);  // round-off length scale of the mesh [m]
  const double epsW = 1e-10 * diag2;            // round-off scale of a 2-D edge function [m^2]

  // Candidate cells: those covering the bounding box, within the material region.
  int c0[3], nc[3], np[3];
  for (int d = 0; d < 3; ++d) {
    const int first = std::max(kWallLayer, static_cast<int>(std::floor((mb.lo[d] - prm.origin[d]) / prm.dx)));
    const int last = std::min(prm.cells[d] - kWallLayer - 1,
                              static_cast<int>(std::ceil((mb.hi[d] - prm.origin[d]) / prm.dx)) - 1);
    c0[d] = first;
    nc[d] = std::max(0, last - first + 1);
    np[d] = nc[d] * perAxis[d];
  }
  auto coord = [&](int d, int m) { return subCentre(prm, d, c0[d] + m / perAxis[d], m % perAxis[d], perAxis[d]); };

  // Triangles bucketed by the xy cells their xy bounding box touches (CSR layout).
  const std::size_t tiles = static_cast<std::size_t>(nc[0]) * nc[1];
  std::vector<std::size_t> start(tiles + 1, 0);
  std::vector<int> bucket;
  std::vector<std::array<int, 4>> span(T.size());  // cell range x0, x1, y0, y1 (empty when x1 < x0)
  for (std::size_t f = 0; f < T.size(); ++f) {
    std::array<int, 4>& s = span[f];
    s = {0, -1, 0, -1};
    if (degenerate(T[f])) continue;
    for (int d = 0; d < 2; ++d) {
      double lo = INFINITY, hi = -INFINITY;
      for (int c = 0; c < 3; ++c) {
        lo = std::min(lo, V[T[f][c]][d]);
        hi = std::max(hi, V[T[f][c]][d]);
      }
      s[2 * d] = std::max(0, static_cast<int>(std::floor((lo - epsL - prm.origin[d]) / prm.dx)) - c0[d]);
      s[2 * d + 1] = std::min(nc[d] - 1, static_cast<int>(std::floor((hi + epsL - prm.origin[d]) / prm.dx)) - c0[d]);
    }
    for (int i = s[0]; i <= s[1]; ++i)
      for (int j = s[2]; j <= s[3]; ++j) ++start[static_cast<std::size_t>(i) * nc[1] + j + 1];
  }
  for (std::size_t t = 0; t < tiles; ++t) start[t + 1] += start[t];
  bucket.resize(start[tiles]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < T.size(); ++f)
      for (int i = span[f][0]; i <= span[f][1]; ++i)
        for (int j = span[f][2]; j <= span[f][3]; ++j) bucket[fill[static_cast<std::size_t>(i) * nc[1] + j]++] = static_cast<int>(f);
  }

  // inside[(m * np[1] + n) * np[2] + k] for the sub-lattice point (m, n, k).
  std::vector<std::uint8_t> inside(static_cast<std::size_t>(np[0]) * np[1] * np[2], 0);
  const long columns = static_cast<long>(np[0]) * np[1];
#pragma omp parallel
  {
    std::vector<double> cross;
#pragma omp for schedule(dynamic, 8)
    for (long q = 0; q < columns; ++q) {
      const int m = static_cast<int>(q / np[1]), n = static_cast<int>(q % np[1]);
      const double X = coord(0, m), Y = coord(1, n);
      const std::size_t tile = static_cast<std::size_t>(m / perAxis[0]) * nc[1] + n / perAxis[1];
      cross.clear();
      bool robust = true;
      for (std::size_t e = start[tile]; e < start[tile + 1]; ++e) {
        const std::array<int, 3>& t = T[bucket[e]];
        const Vec3 &a = V[t[0]], &b = V[t[1]], &c = V[t[2]];
        // 2-D edge functions: twice the signed xy areas of (b, c, P), (c, a, P), (a, b, P).
        const double w0 = (c.x() - b.x()) * (Y - b.y()) - (c.y() - b.y()) * (X - b.x());
        const double w1 = (a.x() - c.x()) * (Y - c.y()) - (a.y() - c.y()) * (X - c.x());
        const double w2 = (b.x() - a.x()) * (Y - a.y()) - (b.y() - a.y()) * (X - a.x());
        if ((w0 > epsW && w1 > epsW && w2 > epsW) || (w0 < -epsW && w1 < -epsW && w2 < -epsW)) {
          cross.push_back((w0 * a.z() + w1 * b.z() + w2 * c.z()) / (w0 + w1 + w2));
        } else if ((w0 >= -epsW && w1 >= -epsW && w2 >= -epsW) || (w0 <= epsW && w1 <= epsW && w2 <= epsW)) {
          robust = false;  // on (or within round-off of) an edge, a vertex or a vertical face
        }
      }
      if (cross.size() % 2 != 0) robust = false;
      std::sort(cross.begin(), cross.end());
      std::size_t below = 0;  // crossings below the current candidate
      const std::size_t base = static_cast<std::size_t>(q) * np[2];
      for (int k = 0; k < np[2]; ++k) {
        const double Z = coord(2, k);
        while (below < cross.size() && cross[below] < Z) ++below;
        const bool nearCrossing = (below < cross.size() && cross[below] - Z <= epsL) ||
                                  (below > 0 && Z - cross[below - 1] <= epsL);
        if (robust && !nearCrossing)
          inside[base + k] = below % 2;
        else
          inside[base + k] = sign * windingNumber(V, T, Vec3(X, Y, Z)) > 0.5;
      }
    }
  }

  const int nsub = perAxis[0] * perAxis[1] * perAxis[2];
  const double vol = prm.dx * prm.dx * prm.dx / nsub;
  const double mass = prm.material.density * vol;
  std::size_t added = 0;
  for (int i = 0; i < nc[0]; ++i)
    for (int j = 0; j < nc[1]; ++j)
      for (int k = 0; k < nc[2]; ++k)
        for (int a = 0; a < perAxis[0]; ++a)
          for (int b = 0; b < perAxis[1]; ++b)
            for (int c = 0; c < perAxis[2]; ++c) {
              const int m = i * perAxis[0] + a, n = j * perAxis[1] + b, l = k * perAxis[2] + c;
              if (!inside[(static_cast<std::size_t>(m) * np[1] + n) * np[2] + l]) continue;
              const double x[3] = {subCentre(prm, 0, c0[0] + i, a, perAxis[0]), subCentre(prm, 1, c0[1] + j, b, perAxis[1]),
                                   subCentre(prm, 2, c0[2] + k, c, perAxis[2])};
              out.add(x, mass, vol, velocity);
              ++added;
            }
  if (added == 0) {
    std::ostringstream range;
    range << "> 0 (the mesh must be thicker than the point spacing dx / perAxis = " << prm.dx / perAxis[0] << ", "
          << prm.dx / perAxis[1] << ", " << prm.dx / perAxis[2] << " m)";
    throwParameter(meshLabel(name) + " particle count", 0, "", range.str());
  }
  return added;
}

std::size_t seedBox(const MpmParams& prm, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    const std::array<int, 3>& perAxis, const std::array<double, 3>& velocity, SeedSink& out) {
  const char* axis[3] = {"x", "y", "z"};
  int c0[3], c1[3];
  checkPerAxis(perAxis);
  for (int d = 0; d < 3; ++d) {
    const double a = prm.origin[d] + kWallLayer * prm.dx, b = prm.origin[d] + (prm.cells[d] - kWallLayer) * prm.dx;
    std::ostringstream range;
    range << "in [" << a << ", " << b << "] m (the grid box less its " << kWallLayer << "-cell wall layers)";
    if (!(lo[d] >= a - 1e-12 * prm.dx && lo[d] <= b)) throwParameter(std::string("lo[") + axis[d] + "]", lo[d], "m", range.str());
    if (!(hi[d] <= b + 1e-12 * prm.dx && hi[d] >= a)) throwParameter(std::string("hi[") + axis[d] + "]", hi[d], "m", range.str());
    // Cells whose centre (origin + (c + 1/2) dx) lies in [lo, hi].
    c0[d] = static_cast<int>(std::ceil((lo[d] - prm.origin[d]) / prm.dx - 0.5 - 1e-9));
    c1[d] = static_cast<int>(std::floor((hi[d] - prm.origin[d]) / prm.dx - 0.5 + 1e-9));
    if (c1[d] < c0[d]) {
      std::ostringstream os;
      os << "> lo[" << axis[d] << "] + about dx so that at least one cell centre lies in the box";
      throwParameter(std::string("hi[") + axis[d] + "]", hi[d], "m", os.str());
    }
  }
  const int n = perAxis[0] * perAxis[1] * perAxis[2];
  const double vol = prm.dx * prm.dx * prm.dx / n;
  const double mass = prm.material.density * vol;
  std::size_t added = 0;
  for (int i = c0[0]; i <= c1[0]; ++i)
    for (int j = c0[1]; j <= c1[1]; ++j)
      for (int k = c0[2]; k <= c1[2]; ++k)
        for (int a = 0; a < perAxis[0]; ++a)
          for (int b = 0; b < perAxis[1]; ++b)
            for (int c = 0; c < perAxis[2]; ++c) {
              const double x[3] = {subCentre(prm, 0, i, a, perAxis[0]), subCentre(prm, 1, j, b, perAxis[1]),
                                   subCentre(prm, 2, k, c, perAxis[2])};
              out.add(x, mass, vol, velocity);
              ++added;
            }
  return added;
}

std::size_t seedBox(const MpmParams& prm, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    const std::array<int, 3>& perAxis, ParticleSet& out) {
  ParticleSetSink sink(out);
  return seedBox(prm, lo, hi, perAxis, {0.0, 0.0, 0.0}, sink);
}

std::size_t seedBox(const MpmParams& prm, const std::array<double, 3>& lo, const std::array<double, 3>& hi, int perCell,
                    ParticleSet& out) {
  const int k = static_cast<int>(std::lround(std::cbrt(static_cast<double>(perCell))));
  if (perCell < 1 || k * k * k != perCell || k > 8)
    throwParameter("particlesPerCell", perCell, "", "a perfect cube in [1, 512] (1, 8, 27, ...)");
  return seedBox(prm, lo, hi, {k, k, k}, out);
}

std::size_t seedMesh(const MpmParams& prm, const std::vector<Vec3>& V, const std::vector<std::array<int, 3>>& T,
                     const std::array<int, 3>& perAxis, const std::array<double, 3>& velocity, ParticleSet& out,
                     const std::string& name) {
  ParticleSetSink sink(out);
  return seedMesh(prm, V, T, perAxis, velocity, sink, name);
}

void ParticleSetSink::add(const double x[3], double mass, double volume0, const std::array<double, 3>& v) {
  for (int d = 0; d < 3; ++d) {
    out_.x.push_back(x[d]);
    out_.v.push_back(v[d]);
    out_.fext.push_back(0.0);
  }
  for (int s = 0; s < 6; ++s) out_.stress.push_back(0.0);
  out_.mass.push_back(mass);
  out_.volume0.push_back(volume0);
  out_.J.push_back(1.0);
  out_.gammaDotP.push_back(0.0);
  out_.phase.push_back(0);
}

void SeededParticles::add(const double x[3], double mass, double volume0, const std::array<double, 3>& v) {
  if (runs_.empty() || runs_.back().mass != mass || runs_.back().volume0 != volume0 || runs_.back().velocity != v)
    runs_.push_back({size(), mass, volume0, v});
  x_.insert(x_.end(), x, x + 3);
}

const ParticleSet& SeededParticles::slice(std::size_t first, std::size_t count) {
  validateSliceRange("seeded particle slice", first, count, size());
  ParticleSet& p = buffer_;
  p.x.assign(x_.begin() + 3 * first, x_.begin() + 3 * (first + count));
  p.v.resize(3 * count);
  p.stress.assign(6 * count, 0.0);
  p.mass.resize(count);
  p.volume0.resize(count);
  p.J.assign(count, 1.0);
  p.gammaDotP.assign(count, 0.0);
  p.fext.assign(3 * count, 0.0);
  p.phase.assign(count, 0);
  // the run holding `first`: the last one starting at or before it
  auto run = std::upper_bound(runs_.begin(), runs_.end(), first,
                              [](std::size_t i, const Run& r) { return i < r.first; }) - 1;
  for (std::size_t i = 0; i < count; ++i) {
    while (run + 1 != runs_.end() && (run + 1)->first <= first + i) ++run;
    p.mass[i] = run->mass;
    p.volume0[i] = run->volume0;
    for (int d = 0; d < 3; ++d) p.v[3 * i + d] = run->velocity[d];
  }
  return p;
}

}  // namespace mpm
}  // namespace mpmsdem
