// Error types shared by the whole core. The Python binding translates
// ParameterError into ValueError and RuntimeFailure into RuntimeError.
#pragma once
#include <sstream>
#include <stdexcept>
#include <string>

namespace mpmsdem {

// Bad user input. The message names the parameter, the value and the allowed range,
// e.g. "sweepRadius = 0.06 m: must be in (0, 0.05) m (half the thinnest dimension)".
struct ParameterError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// A run that cannot go on (NaN, blow-up, time step above the critical one in strict mode).
struct RuntimeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Build "<name> = <value> <unit>: must be <range>" and throw ParameterError.
template <typename T>
[[noreturn]] inline void throwParameter(const std::string& name, const T& value, const std::string& unit,
                                        const std::string& range) {
  std::ostringstream os;
  os << name << " = " << value << (unit.empty() ? "" : " ") << unit << ": must be " << range;
  throw ParameterError(os.str());
}

}  // namespace mpmsdem
