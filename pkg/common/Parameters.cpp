#include "common/Parameters.hpp"

#include "common/Error.hpp"

#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace mpmsdem {

namespace {

// An integer bound as the messages give it: 2^30 rather than 1073741824.
std::string integerText(double v) {
  int e = 0;
  if (v >= 1024 && std::frexp(v, &e) == 0.5) return "2^" + std::to_string(e - 1);
  std::ostringstream os;
  os << static_cast<long long>(v);
  return os.str();
}

}  // namespace

std::string intervalText(double lo, bool loInclusive, double hi, bool hiInclusive) {
  std::ostringstream range;
  range << "in " << (loInclusive ? "[" : "(") << lo << ", ";
  if (std::isinf(hi))
    range << "inf)";
  else
    range << hi << (hiInclusive ? "]" : ")");
  return range.str();
}

void checkRange(const std::string& name, double value, const char* unit, double lo, bool loOpen, double hi,
                bool hiOpen) {
  const bool ok = std::isfinite(value) && (loOpen ? value > lo : value >= lo) && (hiOpen ? value < hi : value <= hi);
  // A bound-free entry ("any") refuses only infinities and NaN: "in [-inf, inf)" would not say so.
  if (!ok) throwParameter(name, value, unit, std::isinf(lo) && std::isinf(hi) ? "finite" : intervalText(lo, !loOpen, hi, !hiOpen));
}

void checkParameter(const ParameterSpec& spec, const std::string& name, double value, double lo, double hi) {
  checkRange(name, value, spec.unit, lo, !spec.loInclusive, hi, !spec.hiInclusive);
}

void checkParameter(const ParameterSpec& spec, double value, const std::string& hint) {
  if (hint.empty()) return checkParameter(spec, spec.key, value, spec.lo, spec.hi);
  try {
    checkParameter(spec, spec.key, value, spec.lo, spec.hi);
  } catch (const ParameterError& e) {
    throw ParameterError(std::string(e.what()) + " (" + hint + ")");
  }
}

bool isRequired(const ParameterSpec& spec) { return std::strcmp(spec.defaultText, kRequired) == 0; }

const ParameterSpec& findParameter(const ParameterTable& table, const std::string& key) {
  for (const ParameterSpec& s : table)
    if (key == s.key) return s;
  throw std::logic_error("no parameter '" + key + "' in the table");
}

std::string leafName(const ParameterSpec& spec) {
  const std::string key = spec.key;
  const std::size_t dot = key.rfind('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

std::vector<std::string> sectionKeys(const ParameterTable& table, const std::string& section) {
  std::vector<std::string> out;
  const std::string prefix = section.empty() ? "" : section + ".";
  for (const ParameterSpec& s : table) {
    const std::string key = s.key;
    if (key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = key.substr(prefix.size());
    if (rest.find_first_of(".[") == std::string::npos) out.push_back(rest);
  }
  return out;
}

std::vector<std::string> choices(const ParameterSpec& spec) {
  std::vector<std::string> out;
  std::istringstream is(spec.range);
  for (std::string c; std::getline(is, c, '|');) out.push_back(c);
  return out;
}

std::string rangeText(const ParameterSpec& spec) {
  if (*spec.range && spec.kind != ParameterKind::kChoice) return spec.range;
  switch (spec.kind) {
    case ParameterKind::kNumber:
      return intervalText(spec.lo, spec.loInclusive, spec.hi, spec.hiInclusive);
    case ParameterKind::kInteger:
      return "an integer in [" + integerText(spec.lo) + ", " + integerText(spec.hi) + "]";
    case ParameterKind::kBoolean:
      return "true or false";
    case ParameterKind::kChoice: {
      std::string list;
      for (const std::string& c : choices(spec)) list += (list.empty() ? "one of \"" : ", \"") + c + "\"";
      return list;
    }
    default:
      return "";
  }
}

std::string defaultText(const ParameterSpec& spec) {
  if (*spec.defaultText || std::isnan(spec.defaultValue)) return spec.defaultText;
  std::ostringstream os;
  os << spec.defaultValue;
  return os.str();
}

const char* kindName(ParameterKind kind) {
  switch (kind) {
    case ParameterKind::kNumber: return "number";
    case ParameterKind::kInteger: return "integer";
    case ParameterKind::kBoolean: return "boolean";
    case ParameterKind::kChoice: return "choice";
    case ParameterKind::kText: return "text";
    case ParameterKind::kVector: return "vector";
    default: return "object";
  }
}

}  // namespace mpmsdem
