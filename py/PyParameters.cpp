// Binding of the scene's parameter tables (common/Parameters.hpp): mpmsdem.parameters names the
// Python API's keywords from them and writes docs/parameters.md.
#include <cmath>

#include "PyConvert.hpp"
#include "common/Parameters.hpp"
#include "coupling/BlockParameters.hpp"
#include "scene/SceneParameters.hpp"

namespace mpmsdem {
namespace py {

namespace {

// A number, or None where the entry has none (NaN default, unused bounds).
bp::object numberOrNone(double v, bool has) { return has && !std::isnan(v) ? bp::object(v) : bp::object(); }

bp::dict entry(const ParameterSpec& s, const char* table) {
  const bool numeric = s.kind == ParameterKind::kNumber || s.kind == ParameterKind::kInteger;
  bp::dict d;
  d["table"] = table;
  d["key"] = s.key;
  d["leaf"] = leafName(s);
  d["python"] = s.python;
  d["kind"] = kindName(s.kind);
  d["unit"] = s.unit;
  d["required"] = isRequired(s);
  d["default"] = numberOrNone(s.defaultValue, numeric);
  d["defaultText"] = defaultText(s);
  d["lo"] = numberOrNone(s.lo, numeric);
  d["hi"] = numberOrNone(s.hi, numeric);
  d["loInclusive"] = s.loInclusive;
  d["hiInclusive"] = s.hiInclusive;
  d["range"] = rangeText(s);
  bp::list options;
  if (s.kind == ParameterKind::kChoice)
    for (const std::string& c : choices(s)) options.append(c);
  d["choices"] = options;
  d["equation"] = s.equation;
  d["doc"] = s.doc;
  return d;
}

// Every entry, the flow's table ("scene") then the blocks' ("blocks"), each in its order.
bp::list parameters() {
  bp::list out;
  for (const ParameterSpec& s : mpm::sceneParameter.table()) out.append(entry(s, "scene"));
  for (const ParameterSpec& s : coupling::blockParameter.table()) out.append(entry(s, "blocks"));
  return out;
}

}  // namespace

void exportParameters() {
  bp::def("parameters", parameters,
          "The scene's parameters, one dict each (table, key, leaf, python, kind, unit, required, default, "
          "defaultText, lo, hi, loInclusive, hiInclusive, range, choices, equation, doc), the flow's then the "
          "blocks'.");
}

}  // namespace py
}  // namespace mpmsdem
