#include "mpm/Seeding.hpp"

#include <cmath>
#include <sstream>

#include "common/Error.hpp"
#include "mpm/GridBoundary.hpp"

namespace mpmsdem {
namespace mpm {

std::size_t seedBox(const MpmParams& prm, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    const std::array<int, 3>& perAxis, ParticleSet& out) {
  const char* axis[3] = {"x", "y", "z"};
  int c0[3], c1[3];
  for (int d = 0; d < 3; ++d) {
    if (perAxis[d] < 1 || perAxis[d] > 8) throwParameter(std::string("perAxis[") + axis[d] + "]", perAxis[d], "", "in [1, 8]");
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
              const int cell[3] = {i, j, k}, sub[3] = {a, b, c};
              for (int d = 0; d < 3; ++d)
                out.x.push_back(prm.origin[d] + (cell[d] + (sub[d] + 0.5) / perAxis[d]) * prm.dx);
              for (int d = 0; d < 3; ++d) {
                out.v.push_back(0.0);
                out.fext.push_back(0.0);
              }
              for (int s = 0; s < 6; ++s) out.stress.push_back(0.0);
              out.mass.push_back(mass);
              out.volume0.push_back(vol);
              out.J.push_back(1.0);
              out.gammaDotP.push_back(0.0);
              out.phase.push_back(0);
              ++added;
            }
  return added;
}

std::size_t seedBox(const MpmParams& prm, const std::array<double, 3>& lo, const std::array<double, 3>& hi, int perCell,
                    ParticleSet& out) {
  const int k = static_cast<int>(std::lround(std::cbrt(static_cast<double>(perCell))));
  if (perCell < 1 || k * k * k != perCell || k > 8)
    throwParameter("particlesPerCell", perCell, "", "a perfect cube in [1, 512] (1, 8, 27, ...)");
  return seedBox(prm, lo, hi, {k, k, k}, out);
}

}  // namespace mpm
}  // namespace mpmsdem
