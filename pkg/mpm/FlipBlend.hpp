// The FLIP/PIC blend of Eq 4 as one value. Eq 4's PIC part replaces a particle's velocity by the
// grid's, which the quadratic B-spline transfers (P2G then G2P) smooth by (dx^2/4) lap(v):
// handing PIC the share 1 - alpha of the velocity once per step of length dt acts as a viscosity
// nu = (1 - alpha) dx^2 / (4 dt) on the resolved flow. So neither a blend per step (the damping
// then follows dt) nor one per unit time (it then follows dx^2) keeps the flow when the step or
// the grid changes; a viscosity does (docs/physics.md, "The blend as a viscosity").
//
// A blend is one of three kinds, each made by its own constructor that refuses what the kind
// cannot mean, so no combination of numbers is left to check afterwards:
//   viscosity(nu)             a step of length dt hands PIC the share x = 4 nu dt / dx^2 and keeps
//                             1 - x of FLIP, which needs dt <= dx^2 / (4 nu) (stepLimit; the
//                             solver's stable step respects it). Keeping exp(-x) instead, as
//                             before commit 7fe22ea, gave the flow nu (1 - e^-x) / x, not nu: a
//                             viscosity that fell under refinement (docs/coupled-results.md,
//                             "Why the held viscosity does not hold");
//   alphaPer(alpha, dt_ref)   alpha kept per dt_ref of simulated time: alpha^(dt / dt_ref), the
//                             same damping per second at any step (the paper's: 0.99 per 5e-6 s);
//   alphaPerStep(alpha)       alpha per step, Eq 4 as written: the damping follows the step.
// The scene keys and their ranges: "flip_viscosity", "flip_alpha", "flip_reference_dt" of
// mpm/MpmParameters (docs/parameters.md); the errors name those keys.
#pragma once
#include <cmath>
#include <limits>
#include <string>

namespace mpmsdem {
namespace mpm {

class FlipBlend {
 public:
  enum class Kind { kViscosity, kAlphaPerTime, kAlphaPerStep };

  // The paper's step (§3.1, Appendix D), the reference of its alpha 0.99 [s].
  static constexpr double kPaperStep = 5e-6;
  // Chosen by measurement: 200 /s at dx 0.01 m, where the granular column collapse (a = 2) runs
  // out to 2.8 L_i against Lube et al.'s 3.02. The paper's blend, alpha 0.99 per kPaperStep at
  // dx 0.01 m, is 0.0503 m^2/s: it brings the §3.2 and §3.3 arrival times onto the paper's at its
  // resolution and stops that column at 1.2 L_i.
  static constexpr double kDefaultViscosity = 0.005;
  // Table 1's alpha: the alpha of a blend given by its reference step alone.
  static constexpr double kTableAlpha = 0.99;

  // The default blend: viscosity(kDefaultViscosity).
  FlipBlend() = default;
  // nu [m^2/s]: > 0 and finite (ParameterError naming flip_viscosity otherwise).
  static FlipBlend viscosity(double nu);
  // alpha in [0, 1] per referenceDt [s] > 0 and finite.
  static FlipBlend alphaPer(double alpha, double referenceDt);
  // alpha in [0, 1] per step.
  static FlipBlend alphaPerStep(double alpha);

  Kind kind() const { return kind_; }
  // Whether the damping follows the step (alpha per step).
  bool perStep() const { return kind_ == Kind::kAlphaPerStep; }
  // The numbers the blend was made from; NaN where its kind has none (alpha of a viscosity,
  // the viscosity of an alpha, the reference step of a blend per step).
  double setViscosity() const { return kind_ == Kind::kViscosity ? value_ : std::nan(""); }
  double setAlpha() const { return kind_ == Kind::kViscosity ? std::nan("") : value_; }
  double referenceDt() const { return kind_ == Kind::kAlphaPerTime ? referenceDt_ : std::nan(""); }

  // The FLIP fraction kept by a step of length dt [s] on a grid of spacing dx [m].
  double alphaFor(double dt, double dx) const {
    switch (kind_) {
      // max: a step up to the solver's 1e-4 round-off slack past stepLimit stays pure PIC
      case Kind::kViscosity: return std::fmax(0.0, 1.0 - 4.0 * value_ * dt / (dx * dx));
      case Kind::kAlphaPerTime: return std::pow(value_, dt / referenceDt_);
      case Kind::kAlphaPerStep: break;
    }
    return value_;
  }
  // The longest step the blend can take on a grid of spacing dx [s]: dx^2 / (4 nu) for a viscosity
  // (the step that hands PIC the whole velocity; a longer one would damp the flow by less than
  // nu), infinite for the kinds given by alpha.
  double stepLimit(double dx) const {
    return kind_ == Kind::kViscosity ? dx * dx / (4.0 * value_) : std::numeric_limits<double>::infinity();
  }
  // The PIC damping rate of such a step [1/s]: the share handed to PIC per second for a
  // viscosity (4 nu / dx^2), -ln(alpha)/dt for the kinds given by alpha (infinite for alpha 0).
  double dampingRate(double dt, double dx) const {
    return kind_ == Kind::kViscosity ? 4.0 * value_ / (dx * dx) : -std::log(alphaFor(dt, dx)) / dt;
  }
  // Its PIC viscosity [m^2/s]: the damping rate times dx^2 / 4.
  double viscosityFor(double dt, double dx) const {
    return kind_ == Kind::kViscosity ? value_ : dampingRate(dt, dx) * dx * dx / 4.0;
  }
  // A step at which the damping rate and viscosity stand for the blend at any step: 1 s for a
  // viscosity, the reference step of an alpha per time; NaN per step (they follow the step).
  double rateStep() const {
    return kind_ == Kind::kViscosity ? 1.0 : kind_ == Kind::kAlphaPerTime ? referenceDt_ : std::nan("");
  }

  // The blend in words at spacing dx, e.g. "PIC viscosity 0.005 m^2/s (PIC damping 200 /s at dx
  // 0.01 m)": what outputs and progress lines record and what a restart compares (the text of
  // each kind is fixed: stored runs hold it).
  std::string describe(double dx) const;

  bool operator==(const FlipBlend& o) const {
    return kind_ == o.kind_ && value_ == o.value_ && (kind_ != Kind::kAlphaPerTime || referenceDt_ == o.referenceDt_);
  }
  bool operator!=(const FlipBlend& o) const { return !(*this == o); }

 private:
  FlipBlend(Kind kind, double value, double referenceDt) : kind_(kind), value_(value), referenceDt_(referenceDt) {}
  Kind kind_ = Kind::kViscosity;
  double value_ = kDefaultViscosity;  // the viscosity, or alpha
  double referenceDt_ = 0;            // kAlphaPerTime only
};

}  // namespace mpm
}  // namespace mpmsdem
