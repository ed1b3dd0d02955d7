// The parameters of a scene, each declared once: its key in the scene's JSON, its name in the
// Python API, unit, default, range, the paper's equation and its meaning. The scene readers take
// the range and the default of a value from its entry (scenejson::readNumber), the Python package
// names its keywords from it (mpmsdem.parameters) and docs/parameters.md is generated from it,
// so the range a page states is the one a reader applies. The tables sit beside what they
// describe: the flow model's in pkg/mpm/MpmParameters, the scene's own in pkg/scene/SceneParameters,
// the blocks' in pkg/coupling.
#pragma once
#include <cmath>
#include <string>
#include <vector>

namespace mpmsdem {

// What a value is in the scene's JSON.
enum class ParameterKind { kNumber, kInteger, kBoolean, kChoice, kText, kVector, kObject };

struct ParameterSpec {
  // Scene JSON path, e.g. "material.mu_s"; an entry of a list is "flow_probes[].x", an entry of
  // a map by name "block_materials.<name>.density".
  const char* key;
  // How the Python API names it: a keyword of an engine or of writeScene, or a key of a dict
  // argument (MpmEngine(material={"mu_s": ...})).
  const char* python;
  ParameterKind kind;
  const char* unit;  // SI, "" for a pure number
  // The default of a number or an integer; NaN where it is not one fixed number (defaultText).
  double defaultValue;
  // The default in words where defaultValue does not say it: kRequired, a rule ("run.duration /
  // 20"), a text ("\"auto\""); "" otherwise.
  const char* defaultText;
  // The range of a number or an integer (hi may be infinite; unused for the other kinds).
  double lo, hi;
  bool loInclusive, hiInclusive;
  // kChoice: the choices, "raw|ascii|none". Otherwise the range in words where lo and hi do not
  // say it all, "" where they do: a bound that is another value (mu_2 >= mu_s; lo and hi then
  // hold whatever that value is), the form of a vector or an object.
  const char* range;
  const char* equation;  // where the paper states it, e.g. "Eq B.2"; "" for none
  const char* doc;       // what it means
};

using ParameterTable = std::vector<ParameterSpec>;

// defaultText of a key without which a scene is refused.
constexpr const char* kRequired = "required";

bool isRequired(const ParameterSpec& spec);
// The entry of `key` in `table`; std::logic_error when it has none (a reader asking for a key
// its table lacks is a programming error, not a bad scene).
const ParameterSpec& findParameter(const ParameterTable& table, const std::string& key);
// A folder's parameters: table() lists them, built once on first use by List (the function that
// writes the entries, beside what they describe), and (key) is the entry of a key. A folder
// declares its own in its header:
//   ParameterTable listSolverParameters();
//   inline constexpr ParameterCatalog<listSolverParameters> solverParameter{};
template <ParameterTable (*List)()>
struct ParameterCatalog {
  static const ParameterTable& table() {
    static const ParameterTable built = List();
    return built;
  }
  const ParameterSpec& operator()(const std::string& key) const { return findParameter(table(), key); }
};

// The shorthands the entries are written with: `using namespace parameter_entries;` in a List.
namespace parameter_entries {
using K = ParameterKind;
constexpr double kInf = INFINITY, kNone = NAN;
}  // namespace parameter_entries

// The last part of the key: "mu_s" for "material.mu_s", "x" for "flow_probes[].x".
std::string leafName(const ParameterSpec& spec);
// The leaf names of the entries right under `section` ("run", "flow_probes[]"), in table order.
std::vector<std::string> sectionKeys(const ParameterTable& table, const std::string& section);
// The choices of a kChoice entry, in order.
std::vector<std::string> choices(const ParameterSpec& spec);
// The range in words, as the readers' messages give it: the entry's range text where it has one,
// else "in (0, inf)", "an integer in [4, 2^30]", "one of \"raw\", \"ascii\", \"none\"".
std::string rangeText(const ParameterSpec& spec);
// The default in words: the number, defaultText, or "" when there is none.
std::string defaultText(const ParameterSpec& spec);
const char* kindName(ParameterKind kind);
// "in [lo, hi)", the brackets saying which bounds are allowed; an infinite hi is "inf)".
std::string intervalText(double lo, bool loInclusive, double hi, bool hiInclusive);

// ParameterError "name = value: must be in [lo, hi)" unless value is finite and satisfies
// lo <(=) value <(=) hi (hi may be infinite).
void checkRange(const std::string& name, double value, const char* unit, double lo, bool loOpen, double hi,
                bool hiOpen);
// `value` in [lo, hi] with the entry's open and closed ends and unit: for a bound that is
// another parameter's value (material.mu_2 >= material.mu_s).
void checkParameter(const ParameterSpec& spec, const std::string& name, double value, double lo, double hi);
// `value` in the entry's own range, the message naming its key: for a value that was not read
// from a scene (a struct filled in C++, checked by the solver it builds). `hint`, where given,
// follows the range in parentheses (what to write instead).
void checkParameter(const ParameterSpec& spec, double value, const std::string& hint = "");

}  // namespace mpmsdem
