// libFuzzer target: the mpm.h5 of an earlier run as mpmsdem-run --restart or --flow-from reads it
// (pkg/run/RunScene.cpp; the input chooses which): the stored scene and blend checked against
// this run's scene (io::checkRestartScene, io::checkFlowFromScene: root attributes "parameters",
// parsed as JSON, and "flip_blend"), the number of snapshots, a snapshot read slice by slice into
// a solver with its time and step (io::SnapshotSlices), then for a restart what its output reads
// of the file (io::Hdf5Writer appending: truncateSeriesAfter, dropSnapshotsAfter, a record of
// each series), for a flow the series (io::readSeries, which the tests use).
//
// Structured: libhdf5, which parses the container, is not instrumented, and mutating its bytes
// would mostly exercise its own checks. The input is read as a list of choices (Choices) that
// say how a small file is written with the HDF5 C API, as mpmsdem-run writes it (choice 0, also
// what every choice is past the input's end: the empty input is a valid file) or otherwise:
// which snapshot datasets exist, their rank, extent, datatype and values, the snapshots' time and
// step attributes, the groups and links of /snapshots and /series, and the root attributes, the
// scene's JSON text taken from the input's end. The file is one per process (FuzzInput.hpp's
// scratch folder) with its snapshot files beside it, as a run's output folder holds them.
// Every HDF5 object the readers open must be closed when they return or throw.
#include <hdf5.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "FuzzInput.hpp"
#include "coupling/CoupledScene.hpp"
#include "io/Hdf5Writer.hpp"
#include "io/StoredScene.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"

namespace {

using namespace mpmsdem;

// The scene of the run going on (one block, so --flow-from compares blocks and their materials;
// the +x and +y walls free, so it compares grid cells by side).
const char* const kScene =
    R"({"grid": {"dx": 0.1, "cells": [8, 8, 8]}, "walls": {"+x": "free", "+y": "free"},
        "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65},
        "particles": [], "run": {"duration": 0.1, "dt": 0.0001},
        "block_materials": {"m": {"density": 2500, "flow": {"friction": 0.2}}},
        "blocks": [{"material": "m", "box": [0.1, 0.1, 0.1], "sweep_radius": 0.01, "position": [0.4, 0.4, 0.4]}]})";

// The input as choices, front to back; past its end every choice is 0.
class Choices {
 public:
  Choices(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
  unsigned pick(unsigned count) { return p_ < end_ ? *p_++ % count : 0; }
  std::string bytes(std::size_t length) {
    const std::size_t n = std::min<std::size_t>(length, end_ - p_);
    std::string out(reinterpret_cast<const char*>(p_), n);
    p_ += n;
    return out;
  }
  std::string rest() { return bytes(end_ - p_); }

 private:
  const std::uint8_t* p_;
  const std::uint8_t* end_;
};

// A failed call of this target's own writing is its fault, not the readers': stop.
hid_t must(hid_t id, const char* what) {
  if (id < 0) {
    std::fprintf(stderr, "fuzz_hdf5: writing the input file: %s failed\n", what);
    std::abort();
  }
  return id;
}

struct Id {  // closes an HDF5 identifier of this target's writing (none: negative)
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id() {
    if (id >= 0) close(id);
  }
  operator hid_t() const { return id; }
};

void emptyGroup(hid_t loc, const char* name) {
  must(H5Gclose(must(H5Gcreate2(loc, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name)), name);
}

// ---------------------------------------------------------------- attributes

// How a string attribute is stored: as mpmsdem-run does (a variable-length UTF-8 string) or not.
enum StringForm { kVlenUtf8, kStringAbsent, kNumber, kTwoStrings, kFixedLength, kVlenAscii, kNullSpace, kStringForms };

void writeString(hid_t loc, const char* name, unsigned form, const std::string& text) {
  if (form == kStringAbsent) return;
  if (form == kNumber) {
    Id space{must(H5Screate(H5S_SCALAR), "scalar space"), H5Sclose};
    Id a{must(H5Acreate2(loc, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
    const double v = 1;
    must(H5Awrite(a, H5T_NATIVE_DOUBLE, &v), name);
    return;
  }
  Id type{must(H5Tcopy(H5T_C_S1), "string type"), H5Tclose};
  must(H5Tset_size(type, form == kFixedLength ? std::max<std::size_t>(text.size(), 1) : H5T_VARIABLE), "size");
  must(H5Tset_cset(type, form == kVlenAscii ? H5T_CSET_ASCII : H5T_CSET_UTF8), "cset");
  const hsize_t two = 2;
  Id space{must(form == kTwoStrings   ? H5Screate_simple(1, &two, nullptr)
                : form == kNullSpace ? H5Screate(H5S_NULL)
                                     : H5Screate(H5S_SCALAR),
                "string space"),
           H5Sclose};
  Id a{must(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
  if (form == kNullSpace) return;
  if (form == kFixedLength) {
    std::string padded = text;
    padded.resize(std::max<std::size_t>(text.size(), 1), '\0');
    must(H5Awrite(a, type, padded.data()), name);
    return;
  }
  const char* s[2] = {text.c_str(), text.c_str()};
  must(H5Awrite(a, type, s), name);
}

// How a number attribute (time, step) is stored: as mpmsdem-run does (a scalar of the
// attribute's `usual` type, float64 or int64) or otherwise; arrays and empty shapes of the
// usual type.
enum NumberForm { kUsual, kNumberAbsent, kF64, kI64, kThree, kF32, kU64, kI8, kOneElement, kNoElement, kNullNumber,
                  kStringNumber, kCompound, kNumberForms };

void writeNumber(hid_t loc, const char* name, unsigned form, hid_t usual, double d, long long i) {
  if (form == kNumberAbsent) return;
  if (form == kStringNumber) return writeString(loc, name, kVlenUtf8, std::to_string(d));
  const hsize_t three = 3, one = 1, none = 0;
  Id space{must(form == kThree        ? H5Screate_simple(1, &three, nullptr)
                : form == kOneElement ? H5Screate_simple(1, &one, nullptr)
                : form == kNoElement  ? H5Screate_simple(1, &none, nullptr)
                : form == kNullNumber ? H5Screate(H5S_NULL)
                                      : H5Screate(H5S_SCALAR),
                "attribute space"),
           H5Sclose};
  if (form == kCompound) {
    Id type{must(H5Tcreate(H5T_COMPOUND, sizeof(double)), "compound"), H5Tclose};
    must(H5Tinsert(type, "value", 0, H5T_NATIVE_DOUBLE), "member");
    Id a{must(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
    must(H5Awrite(a, type, &d), name);
    return;
  }
  const hid_t fileType = form == kF64   ? H5T_IEEE_F64LE
                         : form == kI64 ? H5T_STD_I64LE
                         : form == kF32 ? H5T_IEEE_F32LE
                         : form == kU64 ? H5T_STD_U64LE
                         : form == kI8  ? H5T_STD_I8LE
                                        : usual;
  Id a{must(H5Acreate2(loc, name, fileType, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
  if (form == kNullNumber || form == kNoElement) return;
  const double dv[3] = {d, d, d};
  const long long iv[3] = {i, i, i};
  must(H5Tget_class(fileType) == H5T_INTEGER ? H5Awrite(a, H5T_NATIVE_LLONG, iv) : H5Awrite(a, H5T_NATIVE_DOUBLE, dv),
       name);
}

// The values a time or step attribute takes (pairs: as a float, as an integer); entry 0 is the
// snapshot's own.
void attributeValue(unsigned which, double own, double& d, long long& i) {
  const double inf = std::numeric_limits<double>::infinity();
  const double ds[] = {own, std::nan(""), -1, inf, 1e308, 0, -0.0, 1e19};
  const long long is[] = {static_cast<long long>(own), -1, std::numeric_limits<long long>::max(), 0,
                          std::numeric_limits<long long>::min(), 1, 9007199254740993LL, 255};
  d = ds[which];
  i = is[which];
}

// ---------------------------------------------------------------- datasets

// The file type of a dataset: as mpmsdem-run writes it (0) or another number type, or no number.
const hid_t* numberType(unsigned t, bool phase) {
  static const hid_t types[] = {H5T_IEEE_F64LE, H5T_IEEE_F32LE, H5T_STD_I32LE, H5T_STD_I8LE,
                                H5T_STD_U64LE,  H5T_IEEE_F64BE, H5T_STD_I64BE};
  static const hid_t u8 = H5T_STD_U8LE;
  if (t == 0 && phase) return &u8;
  return t < sizeof types / sizeof types[0] ? &types[t] : nullptr;
}
const unsigned kDatasetTypes = 14;

// A datatype holding no numbers (type choices 7 to 13).
hid_t otherType(unsigned t) {
  switch (t) {
    case 7: {
      const hid_t s = H5Tcopy(H5T_C_S1);
      H5Tset_size(s, 8);
      return s;
    }
    case 8: {
      const hid_t s = H5Tcopy(H5T_C_S1);
      H5Tset_size(s, H5T_VARIABLE);
      return s;
    }
    case 9: {
      const hid_t c = H5Tcreate(H5T_COMPOUND, sizeof(double));
      H5Tinsert(c, "value", 0, H5T_NATIVE_DOUBLE);
      return c;
    }
    case 10: {
      const hid_t e = H5Tenum_create(H5T_NATIVE_UINT8);
      for (unsigned char v = 0; v < 3; ++v) H5Tenum_insert(e, v == 0 ? "elastic" : v == 1 ? "flowing" : "gasified", &v);
      return e;
    }
    case 11:
      return H5Tcreate(H5T_OPAQUE, 8);
    case 12: {
      const hsize_t two = 2;
      return H5Tarray_create2(H5T_NATIVE_DOUBLE, 1, &two);
    }
    default:
      return t == 13 ? H5Tvlen_create(H5T_NATIVE_DOUBLE) : H5Tcopy(H5T_STD_B8LE);
  }
}

// Value e (row-major) of a column of a valid snapshot: particles inside the scene's grid
// (positions in [0.2, 0.6] m: its box less the wall layers), at rest, phases 0, 1, 2 in turn.
double validValue(const mpm::ParticleColumn& c, std::size_t e) {
  const std::string name = c.name;
  if (name == "x") return 0.4 + 0.01 * static_cast<double>(e / 3 % 10);
  if (name == "stress") return -100;
  if (name == "density") return 1600;
  if (name == "phase") return static_cast<double>(e % 3);
  if (name == "mass") return 1.6;
  if (name == "volume0") return 1e-3;
  if (name == "J") return 1;
  return 0;  // v, gammaDotP
}

// Dataset c of a snapshot of n particles, as `in` says.
void writeColumn(hid_t loc, const mpm::ParticleColumn& c, std::size_t n, Choices& in) {
  const unsigned shape = in.pick(14), typeChoice = in.pick(kDatasetTypes), poison = in.pick(12), at = in.pick(256);
  enum { kAsWritten, kAbsent, kScalar, kFlat, kWider, kRank3, kRowMore, kRowLess, kGroup, kNull, kHuge, kChunked,
         kDeflated, kFirstChunkOnly };
  if (shape == kAbsent) return;
  if (shape == kGroup) return emptyGroup(loc, c.name);
  const hsize_t w = c.values;
  hsize_t dims[3] = {n, w, 2};
  int rank = w == 1 ? 1 : 2;
  switch (shape) {
    case kScalar: rank = 0; break;
    case kFlat: rank = 1, dims[0] = n * w; break;
    case kWider: rank = 2, dims[1] = w + 1; break;
    case kRank3: rank = 3; break;
    case kRowMore: dims[0] = n + 1; break;
    case kRowLess: dims[0] = n ? n - 1 : 0; break;
    case kHuge: dims[0] = hsize_t(1) << (20 + at % 40); break;
    default: break;
  }
  const bool chunked = shape == kHuge || shape == kChunked || shape == kDeflated || shape == kFirstChunkOnly;
  hsize_t maxDims[3] = {H5S_UNLIMITED, dims[1], dims[2]};
  Id space{must(shape == kNull     ? H5Screate(H5S_NULL)
                : shape == kScalar ? H5Screate(H5S_SCALAR)
                                   : H5Screate_simple(rank, dims, chunked ? maxDims : nullptr),
                "dataset space"),
           H5Sclose};
  Id dcpl{must(H5Pcreate(H5P_DATASET_CREATE), "dcpl"), H5Pclose};
  if (chunked) {
    hsize_t chunk[3] = {shape == kFirstChunkOnly ? 1u : 4u, dims[1], dims[2]};
    must(H5Pset_chunk(dcpl, rank, chunk), "chunk");
    if (shape == kDeflated) must(H5Pset_deflate(dcpl, 1), "deflate");
  }
  const bool phase = c.kind == mpm::ColumnKind::kPhase;
  const hid_t* number = numberType(typeChoice, phase);
  Id other{number ? H5I_INVALID_HID : must(otherType(typeChoice), "type"), H5Tclose};
  Id dset{must(H5Dcreate2(loc, c.name, number ? *number : other.id, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), c.name),
          H5Dclose};
  if (!number || shape == kNull || shape == kHuge) return;  // nothing stored
  hsize_t total = 1;
  for (int d = 0; d < rank; ++d) total *= dims[d];
  if (total == 0) return;
  std::vector<double> values(total);
  for (std::size_t e = 0; e < total; ++e) values[e] = validValue(c, e);
  const double bad[] = {0, std::nan(""), INFINITY, -INFINITY, -1, 0, 1e300, 3, 255, -1e-300, 300, 1e19};
  if (poison) values[at % total] = bad[poison];
  if (shape != kFirstChunkOnly) {
    must(H5Dwrite(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), "values");
    return;
  }
  hsize_t start[3] = {0, 0, 0}, count[3] = {1, dims[1], dims[2]};
  Id fileSpace{must(H5Dget_space(dset), "file space"), H5Sclose};
  must(H5Sselect_hyperslab(fileSpace, H5S_SELECT_SET, start, nullptr, count, nullptr), "row");
  Id memSpace{must(H5Screate_simple(rank, count, nullptr), "row space"), H5Sclose};
  must(H5Dwrite(dset, H5T_NATIVE_DOUBLE, memSpace, fileSpace, H5P_DEFAULT, values.data()), "first row");
}

// Snapshot k's datasets and attributes into `loc`, as `in` says.
void writeSnapshotContents(hid_t loc, long k, Choices& in) {
  const std::size_t n = (in.pick(7) + 3) % 7;  // 3 particles unless the input says 0 to 6
  for (const mpm::ParticleColumn& c : mpm::kParticleColumns) writeColumn(loc, c, n, in);
  double d;
  long long i;
  const unsigned timeForm = in.pick(kNumberForms), timeValue = in.pick(8);
  attributeValue(timeValue, 0.1 * static_cast<double>(k + 1), d, i);
  writeNumber(loc, "time", timeForm, H5T_IEEE_F64LE, d, i);
  const unsigned stepForm = in.pick(kNumberForms), stepValue = in.pick(8);
  attributeValue(stepValue, 1000.0 * static_cast<double>(k + 1), d, i);
  writeNumber(loc, "step", stepForm, H5T_STD_I64LE, d, i);
}

hid_t fileAccess() {
  const hid_t fapl = must(H5Pcreate(H5P_FILE_ACCESS), "fapl");
  H5Pset_file_locking(fapl, 0, 1);
  return fapl;
}

// /snapshots with its snapshot groups, files and links.
void writeSnapshots(hid_t file, const std::filesystem::path& dir, Choices& in) {
  enum { kGroup, kAbsent, kDataset, kDangling };
  const unsigned layout = in.pick(4), count = 1 + in.pick(3), names = in.pick(5);
  if (layout == kAbsent) return;
  if (layout == kDataset || layout == kDangling) {
    if (layout == kDangling) {
      must(H5Lcreate_soft("/nowhere", file, "snapshots", H5P_DEFAULT, H5P_DEFAULT), "soft link");
      return;
    }
    Id space{must(H5Screate(H5S_SCALAR), "space"), H5Sclose};
    Id d{must(H5Dcreate2(file, "snapshots", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "snapshots"),
         H5Dclose};
    return;
  }
  Id group{must(H5Gcreate2(file, "snapshots", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "snapshots"), H5Gclose};
  enum { kInOrder, kFromOne, kWithIncomplete, kGap, kUnpadded };
  if (names == kWithIncomplete) emptyGroup(group, "incomplete");  // what a run killed while it wrote a snapshot leaves
  std::filesystem::create_directories(dir / "mpm.snapshots");
  for (long k = 0; k < static_cast<long>(count); ++k) {
    const long number = names == kFromOne || (names == kGap && k > 0) ? k + 1 : k;
    char name[32];
    std::snprintf(name, sizeof name, names == kUnpadded ? "%ld" : "%06ld", number);
    const std::string file = std::string("mpm.snapshots/") + name + ".h5";
    enum { kInFile, kOwnFile, kMissingFile, kNotHdf5, kDatasetThere, kSoftLink, kBackToFile };
    switch (in.pick(7)) {
      case kInFile: {
        Id g{must(H5Gcreate2(group, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Gclose};
        writeSnapshotContents(g, k, in);
        break;
      }
      case kOwnFile: {  // as a run's output holds them (Hdf5Writer's snapshot files)
        {
          Id fapl{fileAccess(), H5Pclose};
          Id f{must(H5Fcreate((dir / file).c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), "snapshot file"), H5Fclose};
          writeSnapshotContents(f, k, in);
        }
        must(H5Lcreate_external(file.c_str(), "/", group, name, H5P_DEFAULT, H5P_DEFAULT), "external link");
        break;
      }
      case kMissingFile:
        must(H5Lcreate_external("mpm.snapshots/gone.h5", "/", group, name, H5P_DEFAULT, H5P_DEFAULT), "link");
        break;
      case kNotHdf5: {
        std::FILE* f = std::fopen((dir / file).c_str(), "wb");
        if (!f) std::abort();
        std::fputs("not an HDF5 file\n", f);
        std::fclose(f);
        must(H5Lcreate_external(file.c_str(), "/", group, name, H5P_DEFAULT, H5P_DEFAULT), "link");
        break;
      }
      case kDatasetThere: {
        Id space{must(H5Screate(H5S_SCALAR), "space"), H5Sclose};
        Id d{must(H5Dcreate2(group, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name),
             H5Dclose};
        break;
      }
      case kSoftLink:
        must(H5Lcreate_soft("/snapshots/000000", group, name, H5P_DEFAULT, H5P_DEFAULT), "soft link");
        break;
      default:
        must(H5Lcreate_external("mpm.h5", "/snapshots", group, name, H5P_DEFAULT, H5P_DEFAULT), "link");
        break;
    }
  }
}

// A series dataset as Hdf5Writer::appendRow creates it (extendible, chunked), `rows` x `width`
// (rank 1 for width 0), or with the given rank, type and storage.
void writeSeries(hid_t series, const std::string& name, hsize_t rows, hsize_t width, int rank, hid_t type,
                 bool extendible, bool stored, double value) {
  hsize_t dims[3] = {rows, width, 2}, maxDims[3] = {H5S_UNLIMITED, width, 2}, chunk[3] = {64, width, 2};
  Id space{must(H5Screate_simple(rank, dims, extendible ? maxDims : nullptr), "series space"), H5Sclose};
  Id dcpl{must(H5Pcreate(H5P_DATASET_CREATE), "dcpl"), H5Pclose};
  if (extendible) must(H5Pset_chunk(dcpl, rank, chunk), "chunk");
  Id d{must(H5Dcreate2(series, name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), name.c_str()), H5Dclose};
  if (!stored || H5Tget_class(type) != H5T_FLOAT) return;
  hsize_t total = 1;
  for (int k = 0; k < rank; ++k) total *= dims[k];
  std::vector<double> v(total, value);
  for (hsize_t r = 0; std::isfinite(value) && rank == 1 && r < rows; ++r) v[r] = 0.05 * static_cast<double>(r + 1);
  if (total) must(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "series values");
}

// /series: time (records every 0.05 s, past the last snapshot's time) and centre_of_mass, as a
// run writes them, or not.
void writeSeriesGroup(hid_t file, Choices& in) {
  enum { kAsWritten, kAbsent, kTimeRank2, kTimeRank3, kTimeStrings, kSeriesDataset, kGroupInside, kTimeFixedSize,
         kComRank3, kTimeHuge, kLongName, kComWidth2, kTimeNaN, kNoTime, kSeriesChoices };
  const unsigned choice = in.pick(kSeriesChoices);
  if (choice == kAbsent) return;
  if (choice == kSeriesDataset) {
    Id space{must(H5Screate(H5S_SCALAR), "space"), H5Sclose};
    Id d{must(H5Dcreate2(file, "series", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "series"),
         H5Dclose};
    return;
  }
  Id series{must(H5Gcreate2(file, "series", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "series"), H5Gclose};
  const hsize_t rows = 8;
  Id vlen{must(H5Tcopy(H5T_C_S1), "string"), H5Tclose};
  must(H5Tset_size(vlen, H5T_VARIABLE), "vlen");
  if (choice != kNoTime) {
    const int rank = choice == kTimeRank2 ? 2 : choice == kTimeRank3 ? 3 : 1;
    writeSeries(series, "time", choice == kTimeHuge ? hsize_t(1) << 40 : rows, rank == 1 ? 1 : 2, rank,
                choice == kTimeStrings ? vlen.id : H5T_IEEE_F64LE, choice != kTimeFixedSize, choice != kTimeHuge,
                choice == kTimeNaN ? std::nan("") : 0);
  }
  writeSeries(series, "centre_of_mass", rows, choice == kComWidth2 ? 2 : 3, choice == kComRank3 ? 3 : 2,
              H5T_IEEE_F64LE, true, true, 0.4);
  if (choice == kGroupInside) emptyGroup(series, "g");
  if (choice == kLongName) writeSeries(series, std::string(300, 'k'), rows, 1, 1, H5T_IEEE_F64LE, true, true, 1);
}

struct Run {
  mpm::MpmScene scene;
  std::unique_ptr<mpm::MpmSolver> solver;
  std::filesystem::path dir;
  std::string h5;
};

Run& run() {
  static Run r = [] {
    Run out;
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    // HDF5 gives its metadata cache (hundreds of kB) back to malloc at every file close unless
    // its free lists may keep it; under ASan each new one is fresh pages, and a file open took
    // 1 ms instead of 0.15 (the readers open the file several times a run). Bounded (64 MB a
    // kind of list, 16 MB a list), or blocks of every size ever freed would pile up.
    H5set_free_list_limits(64 << 20, 16 << 20, 64 << 20, 16 << 20, 64 << 20, 16 << 20);
    try {
      out.scene = mpm::parseScene(kScene, "fuzz_hdf5 scene");
      (void)coupling::parseBlocks(out.scene.sourceJson);
      out.solver = mpm::makeSolver(out.scene.params, mpm::Backend::Cpu, mpm::Precision::Double);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "fuzz_hdf5: the target's scene: %s\n", e.what());
      std::abort();
    }
    out.dir = fuzz::scratchDir() / "run";
    out.h5 = (out.dir / "mpm.h5").string();
    return out;
  }();
  return r;
}

// The particles of a snapshot into the solver, as the driver loads a restart or a flow.
void load(io::SnapshotSlices& particles) {
  run().solver->setParticles(particles);
  run().solver->setClock(particles.time(), particles.step());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Run& r = run();
  std::error_code ec;
  std::filesystem::remove_all(r.dir, ec);
  std::filesystem::create_directories(r.dir);
  Choices in(data, size);
  enum { kRestart, kFlowFrom };
  const unsigned option = in.pick(2);
  // The snapshot read: a restart's is the last, or the one coupled.checkpoint.json names; a
  // flow's the one front_snapshot.json names. Choices 2 and 3 are out of range (the driver
  // refuses them naming that record).
  const unsigned which = in.pick(4);
  const std::size_t sliceSize = 1 + in.pick(4);
  const unsigned sceneForm = in.pick(kStringForms), sceneText = in.pick(2);
  const unsigned blendForm = in.pick(kStringForms), blendText = in.pick(2);
  {
    Id fapl{fileAccess(), H5Pclose};
    Id file{must(H5Fcreate(r.h5.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), "mpm.h5"), H5Fclose};
    writeSnapshots(file, r.dir, in);
    writeSeriesGroup(file, in);
    const std::string ours = r.scene.params.flip.describe(r.scene.params.dx);
    writeString(file, "flip_blend", blendForm, blendText ? in.bytes(in.pick(256)) : ours);
    writeString(file, "parameters", sceneForm, sceneText ? in.rest() : r.scene.sourceJson);
  }
  const auto snapshot = [&](long count) -> long {
    return which == 0 ? count - 1 : which == 1 ? 0 : which == 2 ? -1 : count;
  };

  if (option == kFlowFrom) {
    fuzz::expectOnlyDocumentedErrors([&] {
      io::checkFlowFromScene(r.scene, r.h5);
      const long count = io::readNumSnapshots(r.h5), index = snapshot(count);
      if (index < 0 || index >= count) return;
      io::SnapshotSlices particles(r.h5, index, sliceSize);
      load(particles);
    });
    fuzz::expectOnlyDocumentedErrors([&] {
      std::size_t width = 0;
      (void)io::readSeries(r.h5, "time");
      (void)io::readSeries(r.h5, "centre_of_mass", &width);
    });
  } else {
    fuzz::expectOnlyDocumentedErrors([&] {
      io::checkRestartScene(r.scene, r.h5);
      const long count = io::readNumSnapshots(r.h5), index = snapshot(count);
      if (index < 0 || index >= count) return;
      {
        io::SnapshotSlices particles(r.h5, index, sliceSize);
        load(particles);
      }
      // What the restart's output then reads of the file (the header it writes again reads
      // nothing): the series and snapshots after its time are dropped, a record appended.
      const double t = r.solver->time() * (1 + 1e-12);
      io::Hdf5Writer out(r.h5, io::Hdf5Writer::Mode::Append, true);
      out.truncateSeriesAfter("time", t);
      out.dropSnapshotsAfter(t);
      out.appendScalar("time", t);
      out.appendVector("centre_of_mass", {0.4, 0.4, 0.4});
    });
  }

  const ssize_t open = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
  if (open != 0) {
    std::fprintf(stderr, "fuzz_hdf5: %zd HDF5 objects left open by the readers\n", open);
    std::abort();
  }
  return 0;
}
