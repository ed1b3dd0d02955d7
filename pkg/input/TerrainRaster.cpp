// ESRI ASCII grid reader (see TerrainRaster.hpp).
#include "input/TerrainRaster.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace io {
namespace {

[[noreturn]] void badRaster(const std::string& path, const std::string& why) {
  throwParameter("terrain file", "'" + path + "'", "", "a readable ESRI ASCII grid (" + why + ")");
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// A whole token as a finite double, or false.
bool number(const std::string& token, double& value) {
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return end && *end == '\0' && end != token.c_str() && std::isfinite(value);
}

}  // namespace

TerrainRaster readEsriAscii(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) badRaster(path, "no such regular file");
  std::ifstream in(path);
  if (!in) badRaster(path, "cannot open the file");
  // The header: "key value" lines until the first token that is a number.
  std::map<std::string, double> header;
  std::string token;
  while (in >> token) {
    double v;
    if (number(token, v)) break;
    const std::string key = lower(token);
    static const char* known[] = {"ncols", "nrows", "xllcorner", "xllcenter", "yllcorner", "yllcenter", "cellsize",
                                  "nodata_value"};
    if (std::find_if(std::begin(known), std::end(known), [&key](const char* k) { return key == k; }) == std::end(known))
      badRaster(path, "unknown header key '" + token + "'");
    if (header.count(key)) badRaster(path, "header key '" + token + "' given twice");
    std::string value;
    if (!(in >> value) || !number(value, v)) badRaster(path, "header key '" + token + "' without a number");
    header[key] = v;
    token.clear();
  }
  for (const char* k : {"ncols", "nrows", "cellsize"})
    if (!header.count(k)) badRaster(path, std::string("no '") + k + "' in the header");
  const bool xCorner = header.count("xllcorner") > 0, yCorner = header.count("yllcorner") > 0;
  if (xCorner == (header.count("xllcenter") > 0)) badRaster(path, "one of xllcorner and xllcenter in the header");
  if (yCorner == (header.count("yllcenter") > 0)) badRaster(path, "one of yllcorner and yllcenter in the header");
  const double cols = header["ncols"], rows = header["nrows"], cell = header["cellsize"];
  if (cols != std::floor(cols) || cols < 2 || cols > 1e8) badRaster(path, "ncols must be a whole number >= 2");
  if (rows != std::floor(rows) || rows < 2 || rows > 1e8) badRaster(path, "nrows must be a whole number >= 2");
  if (!(cell > 0)) badRaster(path, "cellsize must be > 0");
  if (cols * rows > 2147483647.0) badRaster(path, "ncols x nrows must be < 2^31");
  TerrainRaster r;
  r.nx = static_cast<int>(cols);
  r.ny = static_cast<int>(rows);
  r.spacing = cell;
  r.x0 = xCorner ? header["xllcorner"] + 0.5 * cell : header["xllcenter"];
  r.y0 = yCorner ? header["yllcorner"] + 0.5 * cell : header["yllcenter"];
  if (!std::isfinite(r.x0) || !std::isfinite(r.y0) || !std::isfinite(r.x0 + (r.nx - 1) * cell) ||
      !std::isfinite(r.y0 + (r.ny - 1) * cell))
    badRaster(path, "the grid's extent from its corner and cellsize lies beyond the range of a double");
  const bool hasNoData = header.count("nodata_value") > 0;
  const double noData = hasNoData ? header["nodata_value"] : 0;
  // The values in file order, kept as they are read: the header alone never makes the reader
  // hold more than the file does (ncols x nrows may be up to 2^31 in a file of a few bytes).
  const std::size_t total = static_cast<std::size_t>(r.nx) * r.ny;
  std::vector<double> values;
  std::size_t missing = 0, firstMissing = 0;
  while (!token.empty() || in >> token) {
    double v;
    if (!number(token, v))
      badRaster(path, "'" + token + "' is not a number (value " + std::to_string(values.size() + 1) + ")");
    token.clear();
    if (values.size() == total) badRaster(path, "more than ncols x nrows = " + std::to_string(total) + " values");
    if (hasNoData && v == noData) {
      if (missing++ == 0) firstMissing = values.size();
    }
    values.push_back(v);
  }
  const std::size_t count = values.size();
  if (count < total)
    badRaster(path, "ncols x nrows = " + std::to_string(total) + " values expected, " + std::to_string(count) + " found");
  if (missing)
    badRaster(path, std::to_string(missing) + " no-data values, the first at column " +
                        std::to_string(firstMissing % r.nx) + ", row " + std::to_string(firstMissing / r.nx) +
                        " from the north: fill them before using the raster as a terrain");
  r.heights.resize(total);
  for (std::size_t k = 0; k < total; ++k) {
    const std::size_t row = k / r.nx, col = k % r.nx;  // row 0 is the north one
    r.heights[col * r.ny + (static_cast<std::size_t>(r.ny) - 1 - row)] = values[k];
  }
  return r;
}

}  // namespace io
}  // namespace mpmsdem
