#include "io/VtkWriter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace io {

namespace {

// One DataArray: values are held as bytes of the VTK type named in `type`.
struct Array {
  std::string name;
  std::string type;  // "Float32", "Int64", "Int32", "UInt8"
  int components = 1;
  std::vector<unsigned char> bytes;

  std::size_t elementSize() const { return type == "UInt8" ? 1 : (type == "Int64" ? 8 : 4); }
  std::size_t values() const { return bytes.size() / elementSize(); }
};

template <typename T>
Array makeArray(const std::string& name, const std::string& type, int components, const std::vector<T>& v) {
  Array a{name, type, components, {}};
  a.bytes.resize(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(a.bytes.data(), v.data(), a.bytes.size());
  return a;
}

bool hostIsLittleEndian() {
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void writeAsciiValues(std::ostream& os, const Array& a) {
  const std::size_t n = a.values();
  const std::size_t perLine = 3 * static_cast<std::size_t>(a.components);
  for (std::size_t i = 0; i < n; ++i) {
    if (a.type == "Float32") {
      float f;
      std::memcpy(&f, &a.bytes[4 * i], 4);
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(f));
      os << buf;
    } else if (a.type == "Int64") {
      std::int64_t k;
      std::memcpy(&k, &a.bytes[8 * i], 8);
      os << k;
    } else if (a.type == "Int32") {
      std::int32_t k;
      std::memcpy(&k, &a.bytes[4 * i], 4);
      os << k;
    } else {
      os << static_cast<unsigned>(a.bytes[i]);
    }
    os << ((i + 1) % perLine == 0 || i + 1 == n ? '\n' : ' ');
  }
}

// Writes DataArray elements (inline for Ascii, offsets into the appended section otherwise)
// and, for AppendedRaw, collects the arrays to append in order.
class PolyDataFile {
 public:
  PolyDataFile(VtkEncoding enc) : enc_(enc) {}

  void dataArray(std::ostream& os, const Array& a, const char* indent) {
    os << indent << "<DataArray type=\"" << a.type << "\" Name=\"" << a.name << "\" NumberOfComponents=\""
       << a.components << "\" format=\"" << (enc_ == VtkEncoding::Ascii ? "ascii" : "appended") << "\"";
    if (enc_ == VtkEncoding::Ascii) {
      os << ">\n";
      writeAsciiValues(os, a);
      os << indent << "</DataArray>\n";
    } else {
      os << " offset=\"" << offset_ << "\"/>\n";
      offset_ += sizeof(std::uint64_t) + a.bytes.size();
      appended_.push_back(&a);
    }
  }

  void finish(std::ostream& os) {
    if (enc_ == VtkEncoding::AppendedRaw) {
      os << "  <AppendedData encoding=\"raw\">\n   _";
      for (const Array* a : appended_) {
        const std::uint64_t nbytes = a->bytes.size();
        os.write(reinterpret_cast<const char*>(&nbytes), sizeof nbytes);
        os.write(reinterpret_cast<const char*>(a->bytes.data()), static_cast<std::streamsize>(nbytes));
      }
      os << "\n  </AppendedData>\n";
    }
    os << "</VTKFile>\n";
  }

 private:
  VtkEncoding enc_;
  std::size_t offset_ = 0;
  std::vector<const Array*> appended_;
};

// Writes a PolyData file with points, point data, and either verts or polys as cells.
void writePolyData(const std::string& path, VtkEncoding enc, const Array& points, const std::vector<Array>& pointData,
                   const char* cellKind, std::size_t numCells, const Array& connectivity, const Array& offsets,
                   const std::vector<Array>& cellData, const std::string& pointAttributes) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream os(tmp, std::ios::binary);
    if (!os) throw RuntimeFailure("VTK file '" + path + "': cannot open '" + tmp + "' for writing");
    const std::size_t numPoints = points.values() / 3;
    const bool verts = std::string(cellKind) == "Verts";
    os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\""
       << (hostIsLittleEndian() ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n"
       << " <PolyData>\n  <Piece NumberOfPoints=\"" << numPoints << "\" NumberOfVerts=\"" << (verts ? numCells : 0)
       << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" << (verts ? 0 : numCells) << "\">\n";
    PolyDataFile f(enc);
    os << "   <PointData" << pointAttributes << ">\n";
    for (const Array& a : pointData) f.dataArray(os, a, "    ");
    os << "   </PointData>\n   <CellData>\n";
    for (const Array& a : cellData) f.dataArray(os, a, "    ");
    os << "   </CellData>\n   <Points>\n";
    f.dataArray(os, points, "    ");
    os << "   </Points>\n   <" << cellKind << ">\n";
    f.dataArray(os, connectivity, "    ");
    f.dataArray(os, offsets, "    ");
    os << "   </" << cellKind << ">\n  </Piece>\n </PolyData>\n";
    f.finish(os);
    if (!os) throw RuntimeFailure("VTK file '" + path + "': write failed (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw RuntimeFailure("VTK file '" + path + "': cannot rename from '" + tmp + "': " + ec.message());
}

std::string formatTime(double t) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", t);
  return buf;
}

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string xmlUnescape(const std::string& s) {
  static const std::pair<const char*, char> table[] = {{"&amp;", '&'}, {"&quot;", '"'}, {"&lt;", '<'}, {"&gt;", '>'}};
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    bool replaced = false;
    for (const auto& [entity, c] : table) {
      const std::size_t len = std::strlen(entity);
      if (s.compare(i, len, entity) == 0) {
        out += c;
        i += len;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += s[i++];
  }
  return out;
}

}  // namespace

void writeParticlesVtp(const std::string& path, const mpm::ParticleSet& p, VtkEncoding encoding) {
  const std::size_t n = p.size();
  p.validateSizes();

  std::vector<float> x(p.x.begin(), p.x.end()), v(p.v.begin(), p.v.end());
  std::vector<float> stress(9 * n), pressure(n), density(n), gdp(p.gammaDotP.begin(), p.gammaDotP.end());
  for (std::size_t i = 0; i < n; ++i) {
    const double* s = &p.stress[6 * i];  // xx yy zz yz xz xy
    const double full[9] = {s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]};
    for (int k = 0; k < 9; ++k) stress[9 * i + k] = static_cast<float>(full[k]);
    pressure[i] = static_cast<float>(-(s[0] + s[1] + s[2]) / 3.0);
    density[i] = static_cast<float>(p.density(i));
  }
  std::vector<Array> pointData;
  pointData.push_back(makeArray("velocity", "Float32", 3, v));
  pointData.push_back(makeArray("stress", "Float32", 9, stress));
  pointData.push_back(makeArray("pressure", "Float32", 1, pressure));
  pointData.push_back(makeArray("density", "Float32", 1, density));
  pointData.push_back(makeArray("gammaDotP", "Float32", 1, gdp));
  pointData.push_back(makeArray("phase", "UInt8", 1, p.phase));

  // One poly-vertex cell holding every point (so ParaView draws them in any representation).
  std::vector<std::int64_t> conn(n), offs(n > 0 ? 1 : 0, static_cast<std::int64_t>(n));
  for (std::size_t i = 0; i < n; ++i) conn[i] = static_cast<std::int64_t>(i);
  writePolyData(path, encoding, makeArray("Points", "Float32", 3, x), pointData, "Verts", n > 0 ? 1 : 0,
                makeArray("connectivity", "Int64", 1, conn), makeArray("offsets", "Int64", 1, offs), {},
                " Scalars=\"pressure\" Vectors=\"velocity\" Tensors=\"stress\"");
}

void writeRigidSurfacesVtp(const std::string& path, const std::vector<RigidSurface>& bodies, VtkEncoding encoding) {
  std::vector<float> pts;
  std::vector<std::int64_t> conn, offs;
  std::vector<std::int32_t> ids;
  std::int64_t base = 0;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const RigidSurface& s = bodies[b];
    const auto nv = static_cast<std::int64_t>(s.vertices.size());
    for (const auto& vtx : s.vertices)
      for (double c : vtx) pts.push_back(static_cast<float>(c));
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const int idx = s.triangles[t][k];
        if (idx < 0 || idx >= nv) {
          std::ostringstream name;
          name << "body " << s.id << " triangle " << t << " vertex index";
          throwParameter(name.str(), idx, "", "in [0, " + std::to_string(nv) + ") (the body's vertex count)");
        }
        conn.push_back(base + idx);
      }
      offs.push_back(static_cast<std::int64_t>(conn.size()));
      ids.push_back(s.id);
    }
    base += nv;
  }
  writePolyData(path, encoding, makeArray("Points", "Float32", 3, pts), {}, "Polys", ids.size(),
                makeArray("connectivity", "Int64", 1, conn), makeArray("offsets", "Int64", 1, offs),
                {makeArray("bodyId", "Int32", 1, ids)}, "");
}

// ------------------------------------------------------------------------------ PVD

PvdCollection::PvdCollection(const std::string& path, bool append) : path_(path) {
  if (append && std::filesystem::exists(path)) {
    std::ifstream is(path);
    std::stringstream ss;
    ss << is.rdbuf();
    const std::string text = ss.str();
    const std::regex ds("<DataSet\\s+timestep=\"([^\"]*)\"\\s+group=\"[^\"]*\"\\s+part=\"([^\"]*)\"\\s+file=\"([^\"]*)\"");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), ds); it != std::sregex_iterator(); ++it) {
      const std::smatch& m = *it;
      entries_.push_back({std::stod(m[1].str()), std::stoi(m[2].str()), xmlUnescape(m[3].str())});
    }
  }
  rewrite();
}

void PvdCollection::add(double time, const std::string& file, int part) {
  entries_.push_back({time, part, file});
  rewrite();
}

double PvdCollection::dropAfter(double time) {
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.time > time; }),
                 entries_.end());
  rewrite();
  return entries_.empty() ? std::nan("") : entries_.back().time;
}

void PvdCollection::rewrite() const {
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream os(tmp);
    if (!os) throw RuntimeFailure("PVD file '" + path_ + "': cannot open '" + tmp + "' for writing");
    os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\""
       << (hostIsLittleEndian() ? "LittleEndian" : "BigEndian") << "\">\n <Collection>\n";
    for (const Entry& e : entries_)
      os << "  <DataSet timestep=\"" << formatTime(e.time) << "\" group=\"\" part=\"" << e.part << "\" file=\""
         << xmlEscape(e.file) << "\"/>\n";
    os << " </Collection>\n</VTKFile>\n";
    if (!os) throw RuntimeFailure("PVD file '" + path_ + "': write failed (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path_, ec);
  if (ec) throw RuntimeFailure("PVD file '" + path_ + "': cannot rename from '" + tmp + "': " + ec.message());
}

}  // namespace io
}  // namespace mpmsdem
