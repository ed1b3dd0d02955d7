#include "io/VtkWriter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>

#include "common/Error.hpp"

namespace mpmsdem {
namespace io {

namespace {

// One DataArray: values are held as bytes of the VTK type named in `type`.
// A streamed array (AppendedRaw only) holds no bytes: streamedBytes of it are written into
// its place in the appended section afterwards (writePolyData's `stream`).
struct Array {
  std::string name;
  std::string type;  // "Float32", "Int64", "Int32", "UInt8"
  int components = 1;
  std::vector<unsigned char> bytes;
  bool streamed = false;
  std::size_t streamedBytes = 0;

  std::size_t elementSize() const { return type == "UInt8" ? 1 : (type == "Int64" ? 8 : 4); }
  std::size_t byteCount() const { return streamed ? streamedBytes : bytes.size(); }
  std::size_t values() const { return byteCount() / elementSize(); }
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
      offset_ += sizeof(std::uint64_t) + a.byteCount();
      appended_.push_back(&a);
    }
  }

  // The appended section and the end of the file; a streamed array's bytes are left as a
  // hole whose file position dataAt() gives.
  void finish(std::ostream& os) {
    if (enc_ == VtkEncoding::AppendedRaw) {
      os << "  <AppendedData encoding=\"raw\">\n   _";
      for (const Array* a : appended_) {
        const std::uint64_t nbytes = a->byteCount();
        os.write(reinterpret_cast<const char*>(&nbytes), sizeof nbytes);
        if (a->streamed) {
          streamedAt_.emplace_back(a, os.tellp());
          os.seekp(static_cast<std::streamoff>(nbytes), std::ios::cur);
        } else {
          os.write(reinterpret_cast<const char*>(a->bytes.data()), static_cast<std::streamsize>(nbytes));
        }
      }
      os << "\n  </AppendedData>\n";
    }
    os << "</VTKFile>\n";
  }

  std::streampos dataAt(const Array& a) const {
    for (const auto& [array, at] : streamedAt_)
      if (array == &a) return at;
    throw RuntimeFailure("VTK writer: array '" + a.name + "' is not streamed");
  }

 private:
  VtkEncoding enc_;
  std::size_t offset_ = 0;
  std::vector<const Array*> appended_;
  std::vector<std::pair<const Array*, std::streampos>> streamedAt_;
};

// Writes the bytes of streamed arrays into their places: stream(os, dataAt).
using ArrayStreamer = std::function<void(std::ostream&, const std::function<std::streampos(const Array&)>&)>;

// Writes a PolyData file with points, point data, and either verts or polys as cells; with
// streamed arrays, `stream` writes their bytes before the file is closed and renamed.
void writePolyData(const std::string& path, VtkEncoding enc, const Array& points, const std::vector<Array>& pointData,
                   const char* cellKind, std::size_t numCells, const Array& connectivity, const Array& offsets,
                   const std::vector<Array>& cellData, const std::string& pointAttributes,
                   const ArrayStreamer& stream = {}) {
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
    if (stream) stream(os, [&f](const Array& a) { return f.dataAt(a); });
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
  mpm::WholeParticleSet whole(p);
  writeParticlesVtp(path, whole, encoding);
}

namespace {

// The per-point arrays of a particle file (point data, then the points, then the vertex
// cell's connectivity) and their bytes for particles [first, first + p.size()).
struct ParticleColumn {
  const char* name;
  const char* type;
  int components;
  std::size_t bytesPerParticle;
};
const ParticleColumn kParticleColumns[] = {
    {"velocity", "Float32", 3, 12}, {"stress", "Float32", 9, 36},   {"pressure", "Float32", 1, 4},
    {"density", "Float32", 1, 4},   {"gammaDotP", "Float32", 1, 4}, {"phase", "UInt8", 1, 1},
    {"Points", "Float32", 3, 12},   {"connectivity", "Int64", 1, 8}};
constexpr int kPointDataColumns = 6;

void particleColumnBytes(int column, const mpm::ParticleSet& p, std::size_t first, std::vector<unsigned char>& out) {
  const std::size_t n = p.size();
  out.resize(n * kParticleColumns[column].bytesPerParticle);
  unsigned char* o = out.data();
  auto put = [&o](auto value) {
    std::memcpy(o, &value, sizeof value);
    o += sizeof value;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double* s = &p.stress[6 * i];  // xx yy zz yz xz xy
    switch (column) {
      case 0:
        for (int d = 0; d < 3; ++d) put(static_cast<float>(p.v[3 * i + d]));
        break;
      case 1: {
        const double full[9] = {s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]};
        for (double c : full) put(static_cast<float>(c));
        break;
      }
      case 2:
        put(static_cast<float>(-(s[0] + s[1] + s[2]) / 3.0));
        break;
      case 3:
        put(static_cast<float>(p.density(i)));
        break;
      case 4:
        put(static_cast<float>(p.gammaDotP[i]));
        break;
      case 5:
        put(p.phase[i]);
        break;
      case 6:
        for (int d = 0; d < 3; ++d) put(static_cast<float>(p.x[3 * i + d]));
        break;
      default:
        put(static_cast<std::int64_t>(first + i));
    }
  }
}

}  // namespace

// AppendedRaw streams the arrays slice by slice into their places in the file, so only a
// slice of the particles is on the host; Ascii (small debugging files) gathers them.
void writeParticlesVtp(const std::string& path, mpm::ParticleSlices& particles, VtkEncoding encoding) {
  const std::size_t n = particles.size();
  constexpr int kColumns = sizeof kParticleColumns / sizeof kParticleColumns[0];
  const bool stream = encoding == VtkEncoding::AppendedRaw;
  std::vector<Array> arrays;
  for (const ParticleColumn& c : kParticleColumns) {
    Array a{c.name, c.type, c.components, {}};
    a.streamed = stream;
    a.streamedBytes = stream ? n * c.bytesPerParticle : 0;
    arrays.push_back(std::move(a));
  }
  std::vector<unsigned char> bytes;
  auto forSlices = [&](auto&& fn) {
    mpm::forEachSlice(particles, [&](std::size_t first, const mpm::ParticleSet& p) {
      p.validateSizes(false);
      for (int k = 0; k < kColumns; ++k) {
        particleColumnBytes(k, p, first, bytes);
        fn(k, first, bytes);
      }
    });
  };
  if (!stream)
    forSlices([&](int k, std::size_t, const std::vector<unsigned char>& b) {
      arrays[k].bytes.insert(arrays[k].bytes.end(), b.begin(), b.end());
    });
  // One poly-vertex cell holding every point (so ParaView draws them in any representation).
  const std::vector<std::int64_t> offs(n > 0 ? 1 : 0, static_cast<std::int64_t>(n));
  const std::vector<Array> pointData(arrays.begin(), arrays.begin() + kPointDataColumns);
  const Array& points = arrays[kPointDataColumns];
  const Array& connectivity = arrays[kPointDataColumns + 1];
  ArrayStreamer streamer;
  if (stream)
    streamer = [&](std::ostream& os, const std::function<std::streampos(const Array&)>& dataAt) {
      forSlices([&](int k, std::size_t first, const std::vector<unsigned char>& b) {
        const Array& a = k < kPointDataColumns ? pointData[k] : arrays[k];
        os.seekp(dataAt(a) + static_cast<std::streamoff>(first * kParticleColumns[k].bytesPerParticle));
        os.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
      });
    };
  writePolyData(path, encoding, points, pointData, "Verts", n > 0 ? 1 : 0, connectivity,
                makeArray("offsets", "Int64", 1, offs), {}, " Scalars=\"pressure\" Vectors=\"velocity\" Tensors=\"stress\"",
                streamer);
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

void writeContactsVtp(const std::string& path, const std::vector<ContactPoint>& contacts, VtkEncoding encoding) {
  const std::size_t n = contacts.size();
  std::vector<float> pts, force, fn;
  std::vector<std::int32_t> block, particle;
  std::vector<std::uint8_t> feature;
  std::vector<std::int64_t> conn(n), offs(n);
  for (std::size_t c = 0; c < n; ++c) {
    const ContactPoint& k = contacts[c];
    if (k.feature < 0 || k.feature > 2) throwParameter("contact " + std::to_string(c) + " feature", k.feature, "", "0, 1 or 2");
    for (int d = 0; d < 3; ++d) {
      pts.push_back(static_cast<float>(k.point[d]));
      force.push_back(static_cast<float>(k.force[d]));
    }
    fn.push_back(static_cast<float>(k.normalForce));
    block.push_back(k.blockId);
    particle.push_back(k.particle);
    feature.push_back(static_cast<std::uint8_t>(k.feature));
    conn[c] = static_cast<std::int64_t>(c);
    offs[c] = static_cast<std::int64_t>(c + 1);
  }
  writePolyData(path, encoding, makeArray("Points", "Float32", 3, pts),
                {makeArray("force", "Float32", 3, force), makeArray("normalForce", "Float32", 1, fn),
                 makeArray("blockId", "Int32", 1, block), makeArray("particle", "Int32", 1, particle),
                 makeArray("feature", "UInt8", 1, feature)},
                "Verts", n, makeArray("connectivity", "Int64", 1, conn), makeArray("offsets", "Int64", 1, offs), {},
                " Scalars=\"normalForce\" Vectors=\"force\"");
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

std::size_t PvdCollection::count(int part) const {
  return static_cast<std::size_t>(
      std::count_if(entries_.begin(), entries_.end(), [part](const Entry& e) { return e.part == part; }));
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
