#include "common/SceneJson.hpp"

#include <cmath>
#include <set>

#include "common/Error.hpp"

namespace mpmsdem {
namespace scenejson {

json parse(const std::string& text, const std::string& source) {
  // The callback sees every value as it is read, with its depth (the root is 0): refusing there
  // keeps the parser from building the deep value at all.
  const json::parser_callback_t depth = [&source](int level, json::parse_event_t, json&) {
    if (level > kMaxJsonDepth)
      throw ParameterError(source + ": arrays and objects nested more than " + std::to_string(kMaxJsonDepth) +
                           " levels deep: no scene has them (a scene's deepest keys, a block's core faces, are 5 "
                           "levels down)");
    return true;
  };
  try {
    return json::parse(text, depth);
  } catch (const json::parse_error& e) {
    throw ParameterError(source + ": not valid JSON: " + e.what());
  } catch (const json::exception& e) {  // e.g. 1e999: a number beyond the double range
    throw ParameterError(source + ": a number is out of range (every number must be a finite double, "
                         "|x| < 1.8e308): " + e.what());
  }
}

std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

void checkKeys(const json& obj, const std::string& path, const std::vector<std::string>& allowed) {
  std::set<std::string> ok(allowed.begin(), allowed.end());
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (!ok.count(it.key())) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw ParameterError("unknown key '" + join(path, it.key()) + "': allowed keys" +
                           (path.empty() ? "" : " in '" + path + "'") + " are " + list);
    }
  }
}

void checkKeys(const json& obj, const std::string& path, std::initializer_list<const char*> allowed) {
  checkKeys(obj, path, std::vector<std::string>(allowed.begin(), allowed.end()));
}

const json& requireObject(const json& parent, const std::string& path, const char* key) {
  if (!parent.contains(key)) throw ParameterError("missing required key '" + join(path, key) + "'");
  const json& v = parent.at(key);
  if (!v.is_object()) throwParameter(join(path, key), v.dump(), "", "a JSON object");
  return v;
}

double number(const json& v, const std::string& name) {
  if (!v.is_number()) throwParameter(name, v.dump(), "", "a number");
  return v.get<double>();
}

double requireNumber(const json& obj, const std::string& path, const char* key) {
  if (!obj.contains(key)) throw ParameterError("missing required key '" + join(path, key) + "'");
  return number(obj.at(key), join(path, key));
}

double optNumber(const json& obj, const std::string& path, const char* key, double def) {
  return obj.contains(key) ? number(obj.at(key), join(path, key)) : def;
}

std::array<double, 3> vec3(const json& v, const std::string& name) {
  if (!v.is_array() || v.size() != 3) throwParameter(name, v.dump(), "", "an array of 3 numbers");
  std::array<double, 3> out{};
  for (int a = 0; a < 3; ++a) out[a] = number(v[a], name + "[" + std::to_string(a) + "]");
  return out;
}

double readNumber(const json& obj, const std::string& path, const ParameterSpec& spec) {
  return readNumberIn(obj, path, spec, spec.lo, spec.hi);
}

double readNumberIn(const json& obj, const std::string& path, const ParameterSpec& spec, double lo, double hi) {
  const std::string key = leafName(spec);
  const double v = isRequired(spec) ? requireNumber(obj, path, key.c_str())
                                    : optNumber(obj, path, key.c_str(), spec.defaultValue);
  checkParameter(spec, join(path, key), v, lo, hi);
  return v;
}

double readNumber(const json& obj, const std::string& path, const ParameterSpec& spec, double def) {
  const std::string key = leafName(spec);
  const double v = optNumber(obj, path, key.c_str(), def);
  checkParameter(spec, join(path, key), v, spec.lo, spec.hi);
  return v;
}

long integer(const json& v, const std::string& name, const ParameterSpec& spec) {
  if (!v.is_number_integer()) throwParameter(name, v.dump(), "", rangeText(spec));
  const long n = v.get<long>();
  if (n < spec.lo || n > spec.hi) throwParameter(name, n, "", rangeText(spec));
  return n;
}

bool readBool(const json& obj, const std::string& path, const ParameterSpec& spec, bool def) {
  const std::string key = leafName(spec);
  if (!obj.contains(key)) return def;
  const json& b = obj.at(key);
  if (!b.is_boolean()) throwParameter(join(path, key), b.dump(), "", rangeText(spec));
  return b.get<bool>();
}

std::string readChoice(const json& obj, const std::string& path, const ParameterSpec& spec) {
  const std::string key = leafName(spec);
  if (!obj.contains(key)) return spec.defaultText;
  const json& v = obj.at(key);
  if (v.is_string())
    for (const std::string& c : choices(spec))
      if (v.get<std::string>() == c) return c;
  throwParameter(join(path, key), v.dump(), "", rangeText(spec));
}

}  // namespace scenejson
}  // namespace mpmsdem
