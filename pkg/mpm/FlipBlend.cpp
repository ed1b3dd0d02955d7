#include "mpm/FlipBlend.hpp"

#include <sstream>

#include "common/Error.hpp"
#include "mpm/MpmParameters.hpp"

namespace mpmsdem {
namespace mpm {

// The ranges are the entries' of mpm/MpmParameters, the scene's own.
FlipBlend FlipBlend::viscosity(double nu) {
  checkParameter(solverParameter("flip_viscosity"), nu,
                 "pure FLIP is alpha 1 per step: flip_alpha 1 with flip_reference_dt \"step\"");
  return FlipBlend(Kind::kViscosity, nu, 0);
}

FlipBlend FlipBlend::alphaPer(double alpha, double referenceDt) {
  checkParameter(solverParameter("flip_alpha"), alpha);
  checkParameter(solverParameter("flip_reference_dt"), referenceDt,
                 "alpha is kept per that much simulated time; the paper's blend is 0.99 per 5e-6 s; or \"step\" "
                 "for alpha per step");
  return FlipBlend(Kind::kAlphaPerTime, alpha, referenceDt);
}

FlipBlend FlipBlend::alphaPerStep(double alpha) {
  checkParameter(solverParameter("flip_alpha"), alpha);
  return FlipBlend(Kind::kAlphaPerStep, alpha, 0);
}

std::string FlipBlend::describe(double dx) const {
  std::ostringstream s;
  switch (kind_) {
    case Kind::kViscosity:
      // "share 4 nu dt/dx^2": a run of the exp(-4 nu dt/dx^2) blend (before commit 7fe22ea) recorded
      // the words without it, so a restart from one refuses rather than mix the two.
      s << "PIC viscosity " << value_ << " m^2/s, share 4 nu dt/dx^2 (PIC damping " << std::lround(dampingRate(1.0, dx))
        << " /s at dx " << dx << " m)";
      break;
    case Kind::kAlphaPerTime:
      s << "alpha " << value_ << " per " << referenceDt_ << " s (PIC damping "
        << std::lround(dampingRate(referenceDt_, dx)) << " /s, PIC viscosity " << viscosityFor(referenceDt_, dx)
        << " m^2/s at dx " << dx << " m)";
      break;
    case Kind::kAlphaPerStep:
      s << "alpha " << value_ << " per step (PIC damping -ln(alpha)/dt: it changes with the step)";
      break;
  }
  return s.str();
}

}  // namespace mpm
}  // namespace mpmsdem
