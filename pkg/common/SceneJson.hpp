// Reading the driver's JSON scene files (MPM part: pkg/scene/MpmScene, blocks:
// pkg/coupling/CoupledScene): each accessor names the key path and the allowed range in its
// ParameterError, e.g. "material.poisson_ratio = 0.7: must be in [0, 0.5)".
#pragma once
#include <nlohmann/json.hpp>

#include <array>
#include <initializer_list>
#include <string>
#include <vector>

#include "common/Parameters.hpp"

namespace mpmsdem {
namespace scenejson {

using nlohmann::json;

// The deepest nesting of arrays and objects a scene may have (the deepest real one, a block's
// core faces, is 5 levels). Deeper text is refused while it is parsed: reading, copying and
// printing a JSON value recurse once per level, and text nested 10^5 levels deep (a 200 kB
// file) overflowed the stack of the driver.
constexpr int kMaxJsonDepth = 64;
// Parse a scene's JSON text; ParameterError naming `source` for text that is not JSON, a number
// beyond the range of a double, or nesting deeper than kMaxJsonDepth.
json parse(const std::string& text, const std::string& source);
// "path.key", or "key" at the root.
std::string join(const std::string& path, const std::string& key);
// Every key of `obj` must be in `allowed` (else names the unknown key and the allowed ones).
void checkKeys(const json& obj, const std::string& path, std::initializer_list<const char*> allowed);
void checkKeys(const json& obj, const std::string& path, const std::vector<std::string>& allowed);
const json& requireObject(const json& parent, const std::string& path, const char* key);
double number(const json& v, const std::string& name);
double requireNumber(const json& obj, const std::string& path, const char* key);
double optNumber(const json& obj, const std::string& path, const char* key, double def);
std::array<double, 3> vec3(const json& v, const std::string& name);

// Reading a value through its table entry (common/Parameters.hpp): the message names
// "path.<leaf of the key>" with the entry's unit and range.
// A number: required or the entry's default, in the entry's range.
double readNumber(const json& obj, const std::string& path, const ParameterSpec& spec);
// A number whose default follows from other values (run.output_every: run.duration / 20).
double readNumber(const json& obj, const std::string& path, const ParameterSpec& spec, double def);
// A number, required or the entry's default, in [lo, hi] with the entry's open and closed ends:
// for a bound that is another value (gate.x in the material region).
double readNumberIn(const json& obj, const std::string& path, const ParameterSpec& spec, double lo, double hi);
// An integer in the entry's range (an array's element: name it with `name`).
long integer(const json& v, const std::string& name, const ParameterSpec& spec);
bool readBool(const json& obj, const std::string& path, const ParameterSpec& spec, bool def);
// One of the entry's choices, its default when absent.
std::string readChoice(const json& obj, const std::string& path, const ParameterSpec& spec);

}  // namespace scenejson
}  // namespace mpmsdem
