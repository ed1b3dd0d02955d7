#include "io/Hdf5Writer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include "common/Error.hpp"
#include "scene/MpmScene.hpp"
#include "scene/SceneParameters.hpp"

namespace mpmsdem {
namespace io {

namespace {

// Name of a snapshot group while it is being written; renamed to its index once complete,
// so a run killed mid-snapshot never leaves a half-written numbered snapshot.
const char* const kIncomplete = "incomplete";

// Silence HDF5's own error-stack printing: every failure is turned into an exception here.
void quietHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// The operating system's reason for a failed read or write, from HDF5's error stack (its POSIX
// file driver records errno's message as "error message = '...'"), or "" when it holds none.
std::string systemReason() {
  std::string reason;
  const H5E_walk2_t visit = [](unsigned, const H5E_error2_t* e, void* out) -> herr_t {
    const char* m = e->desc ? std::strstr(e->desc, "error message = '") : nullptr;
    if (!m) return 0;
    m += std::strlen("error message = '");
    const char* end = std::strchr(m, '\'');
    *static_cast<std::string*>(out) = end ? std::string(m, end) : std::string(m);
    return 1;  // the first (innermost) one
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, visit, &reason);
  return reason;
}

// A full disk, a removed folder or a file that cannot be opened: the file, what failed and the
// system's reason where HDF5 recorded one.
[[noreturn]] void fail(const std::string& path, const std::string& what) {
  const std::string reason = systemReason();
  H5Eclear2(H5E_DEFAULT);
  throw RuntimeFailure("HDF5 file '" + path + "': " + what + (reason.empty() ? "" : " (" + reason + ")"));
}

template <typename T>
T check(T id, const std::string& path, const std::string& what) {
  if (id < 0) fail(path, what);
  return id;
}

// RAII holder for an hid_t and its matching close function.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  operator hid_t() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

hid_t fileAccessWithoutLocking() {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_file_locking(fapl, 0, 1);
  return fapl;
}

std::string snapshotName(long index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06ld", index);
  return buf;
}

bool linkExists(hid_t loc, const std::string& name) { return H5Lexists(loc, name.c_str(), H5P_DEFAULT) > 0; }

// `to` becomes a copy of `from`, whole or not at all: a kill during the copy leaves `to` as it
// was (the copy goes to a temporary name, renamed over `to` once complete).
void copyWhole(const std::string& from, const std::string& to) {
  namespace fs = std::filesystem;
  const std::string part = to + ".part";
  std::error_code ec;
  fs::copy_file(from, part, fs::copy_options::overwrite_existing, ec);
  if (!ec) fs::rename(part, to, ec);
  if (ec) fail(to, "cannot copy " + from + " there: " + ec.message());
}

hid_t openOrCreateGroup(hid_t file, const std::string& name, const std::string& path) {
  if (linkExists(file, name))
    return check(H5Gopen2(file, name.c_str(), H5P_DEFAULT), path, "cannot open /" + name + " as a group");
  return check(H5Gcreate2(file, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), path,
               "cannot create group " + name);
}

void writeDoubleAttribute(hid_t loc, const std::string& name, double value, const std::string& path) {
  if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(check(H5Acreate2(loc, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), path,
                    "cannot create attribute " + name),
              H5Aclose);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &value), path, "cannot write attribute " + name);
}

void writeLongAttribute(hid_t loc, const std::string& name, long value, const std::string& path) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(check(H5Acreate2(loc, name.c_str(), H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT), path,
                    "cannot create attribute " + name),
              H5Aclose);
  const long long v = value;
  check(H5Awrite(attr, H5T_NATIVE_LLONG, &v), path, "cannot write attribute " + name);
}

hid_t utf8StringType() {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}

Handle openForReading(const std::string& path) {
  quietHdf5();
  if (!std::filesystem::exists(path)) fail(path, "does not exist");
  Handle fapl(fileAccessWithoutLocking(), H5Pclose);
  return Handle(check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl), path, "cannot open for reading"), H5Fclose);
}

// What the values of an HDF5 datatype class are, for messages.
const char* typeClassName(H5T_class_t c) {
  switch (c) {
    case H5T_INTEGER: return "integers";
    case H5T_FLOAT: return "floating-point numbers";
    case H5T_STRING: return "strings";
    case H5T_BITFIELD: return "bit fields";
    case H5T_OPAQUE: return "opaque bytes";
    case H5T_COMPOUND: return "compound records";
    case H5T_REFERENCE: return "references";
    case H5T_ENUM: return "enumeration members";
    case H5T_VLEN: return "variable-length sequences";
    case H5T_ARRAY: return "arrays";
    default: return "values of no known type";
  }
}

// What a number read from a file may be: HDF5 converts between any integer and floating-point
// types, so both read as a double; a count or an enumeration must have been stored as an integer.
enum class Numbers { kAny, kIntegers };

// `what` (a dataset or attribute, named for messages) must hold numbers of the kind `which`:
// reading strings or records as numbers fails inside HDF5 with no word of why.
void checkNumbers(hid_t type, Numbers which, const std::string& what, const std::string& path) {
  const H5T_class_t c = H5Tget_class(type);
  if (c == H5T_INTEGER || (c == H5T_FLOAT && which == Numbers::kAny)) return;
  fail(path, what + " holds " + typeClassName(c) + ", expected " + (which == Numbers::kAny ? "numbers" : "integers"));
}

// Attribute `name` of the object `where` (e.g. "/snapshots/000002", open as `loc`) read as one
// value of memType into `out`: it must be there, be a number of the kind `which` and hold one
// value (HDF5 writes every value of an array attribute into `out`).
void readNumberAttribute(hid_t loc, const std::string& name, Numbers which, hid_t memType, void* out,
                         const std::string& where, const std::string& path) {
  if (H5Aexists(loc, name.c_str()) <= 0) fail(path, "no attribute " + name + " in " + where);
  const std::string what = "attribute " + name + " of " + where;
  Handle a(check(H5Aopen(loc, name.c_str(), H5P_DEFAULT), path, "cannot open " + what), H5Aclose);
  Handle type(check(H5Aget_type(a), path, "cannot read the type of " + what), H5Tclose);
  checkNumbers(type, which, what, path);
  Handle space(check(H5Aget_space(a), path, "cannot read the shape of " + what), H5Sclose);
  const hssize_t count = H5Sget_simple_extent_npoints(space);
  if (count != 1) fail(path, what + " holds " + std::to_string(count) + " values, expected one");
  check(H5Aread(a, memType, out), path, "cannot read " + what);
}

// Whether the file stores every value of a dataset of extent dims (rank 1 or 2): HDF5 reads the
// values never written as the fill value, so a damaged or foreign file could declare 2^40 rows
// in a few bytes, and a reader would allocate and read them all.
bool storesEveryValue(hid_t dset, int rank, const hsize_t dims[2]) {
  if (dims[0] == 0 || (rank == 2 && dims[1] == 0)) return true;
  H5D_space_status_t status;
  if (H5Dget_space_status(dset, &status) < 0 || status == H5D_SPACE_STATUS_NOT_ALLOCATED) return false;
  if (status == H5D_SPACE_STATUS_ALLOCATED) return true;
  // "Partly": a chunked dataset whose chunks take more room than its values (the last one is
  // whole) or less (compressed); every chunk the extent covers must be stored.
  Handle dcpl(H5Dget_create_plist(dset), H5Pclose);
  hsize_t chunk[2] = {1, 1};
  if (dcpl < 0 || H5Pget_chunk(dcpl, rank, chunk) != rank) return false;
  double needed = 1;  // (as a double: the product of 2 counts may exceed 2^64)
  for (int d = 0; d < rank; ++d) needed *= static_cast<double>(dims[d] / chunk[d] + (dims[d] % chunk[d] != 0));
  Handle space(H5Dget_space(dset), H5Sclose);  // (HDF5 1.10 takes no H5S_ALL here)
  hsize_t stored = 0;
  return H5Dget_num_chunks(dset, space, &stored) >= 0 && static_cast<double>(stored) >= needed;
}

// The extent of `what` (open as dset): rows and values per row (1 for rank 1). Refused unless it
// holds numbers of the kind `which`, has rank 1 or 2 and the file stores all its values.
std::pair<hsize_t, hsize_t> checkedExtent(hid_t dset, Numbers which, const std::string& what, const std::string& path) {
  Handle type(check(H5Dget_type(dset), path, "cannot read the type of " + what), H5Tclose);
  checkNumbers(type, which, what, path);
  Handle space(check(H5Dget_space(dset), path, "cannot read the shape of " + what), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 2) fail(path, what + " has rank " + std::to_string(rank) + ", expected 1 or 2");
  hsize_t dims[2] = {0, 1};
  H5Sget_simple_extent_dims(space, dims, nullptr);  // (it writes `rank` values: checked above)
  if (!storesEveryValue(dset, rank, dims))
    fail(path, what + " declares " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) +
                   " values but the file does not store them all (never written, or a damaged file)");
  return {dims[0], dims[1]};
}

// Read a whole dataset of doubles; `rows`/`cols` receive its shape.
std::vector<double> readArray(hid_t loc, const std::string& name, std::size_t& rows, std::size_t& cols,
                              const std::string& path) {
  if (!linkExists(loc, name)) fail(path, "no dataset " + name);
  Handle dset(check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), path, "cannot open dataset " + name), H5Dclose);
  const auto extent = checkedExtent(dset, Numbers::kAny, "dataset " + name, path);
  rows = extent.first;
  cols = extent.second;
  std::vector<double> out(rows * cols);
  if (!out.empty())
    check(H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), path,
          "cannot read dataset " + name);
  return out;
}

// Name of link k of `group` (`where`, for messages), however long.
std::string linkName(hid_t group, hsize_t k, const std::string& where, const std::string& path) {
  const ssize_t length = H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, k, nullptr, 0, H5P_DEFAULT);
  if (length < 0) fail(path, "cannot list " + where);
  std::string name(static_cast<std::size_t>(length) + 1, '\0');
  check(H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, k, name.data(), name.size(), H5P_DEFAULT), path,
        "cannot list " + where);
  name.resize(static_cast<std::size_t>(length));
  return name;
}

}  // namespace

void skipHdf5CleanupAtExit() { H5dont_atexit(); }

// ------------------------------------------------------------------------------ writer

Hdf5Writer::Hdf5Writer(const std::string& path, Mode mode, bool snapshotFiles)
    : path_(path), snapshotFolder_(snapshotFiles ? snapshotFolder(path) : "") {
  namespace fs = std::filesystem;
  quietHdf5();
  const fs::path folder = fs::path(path).parent_path() / snapshotFolder_;
  std::error_code ec;
  Handle fapl(fileAccessWithoutLocking(), H5Pclose);
  const bool appending = mode == Mode::Append && fs::exists(path);
  if (appending) {
    file_ = check(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl), path, "cannot open for appending");
  } else {
    // a new run: nothing of an earlier one in this place may be restored or linked later
    fs::remove(restartCopyPath(path), ec);
    if (snapshotFiles) fs::remove_all(folder, ec);
    file_ = check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), path, "cannot create");
  }
  // A constructor that throws runs no destructor: close what is open here, or the file would stay
  // open in the process (a later writer or reader of it would fail, and so would its removal on
  // some systems).
  try {
    if (appending && snapshotFiles && fs::is_directory(folder))  // snapshots a killed run left half-written
      for (const auto& entry : fs::directory_iterator(folder))
        if (entry.path().extension() == ".part") fs::remove(entry.path(), ec);
    if (snapshotFiles) {
      fs::create_directories(folder, ec);
      if (ec) fail(path, "cannot create the snapshot folder " + folder.string() + ": " + ec.message());
    }
    series_ = openOrCreateGroup(file_, "series", path);
    snapshots_ = openOrCreateGroup(file_, "snapshots", path);
    if (linkExists(snapshots_, kIncomplete)) H5Ldelete(snapshots_, kIncomplete, H5P_DEFAULT);
    while (linkExists(snapshots_, snapshotName(nextSnapshot_))) ++nextSnapshot_;
    flush();
  } catch (...) {
    close();
    throw;
  }
}

Hdf5Writer::~Hdf5Writer() { close(); }

void Hdf5Writer::close() {
  for (auto& kv : openSeries_) H5Dclose(kv.second);
  openSeries_.clear();
  if (snapshots_ >= 0) H5Gclose(snapshots_);
  if (series_ >= 0) H5Gclose(series_);
  if (file_ >= 0) H5Fclose(file_);
  snapshots_ = series_ = file_ = -1;
}

void Hdf5Writer::flush() { check(H5Fflush(file_, H5F_SCOPE_GLOBAL), path_, "flush failed"); }

std::string Hdf5Writer::snapshotFile(long index) const {
  return (std::filesystem::path(snapshotFolder_) / (snapshotName(index) + ".h5")).string();
}

void Hdf5Writer::commit() {
  flush();
  copyWhole(path_, restartCopyPath(path_));
}

std::string snapshotFolder(const std::string& path) {
  return std::filesystem::path(path).stem().string() + ".snapshots";
}

std::string restartCopyPath(const std::string& path) { return path + ".restart"; }

bool resumeFromCommit(const std::string& path) {
  const std::string copy = restartCopyPath(path);
  if (!std::filesystem::exists(copy)) return false;
  copyWhole(copy, path);
  return true;
}

void Hdf5Writer::setAttribute(const std::string& name, const std::string& value) {
  if (H5Aexists(file_, name.c_str()) > 0) H5Adelete(file_, name.c_str());
  Handle type(utf8StringType(), H5Tclose);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(check(H5Acreate2(file_, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), path_,
                    "cannot create attribute " + name),
              H5Aclose);
  const char* s = value.c_str();
  check(H5Awrite(attr, type, &s), path_, "cannot write attribute " + name);
  flush();
}

void Hdf5Writer::setAttribute(const std::string& name, double value) {
  writeDoubleAttribute(file_, name, value, path_);
  flush();
}

long Hdf5Writer::truncateSeriesAfter(const std::string& timeName, double time, double* lastKept) {
  if (!linkExists(series_, timeName)) return 0;
  std::size_t rows = 0, cols = 0;
  const std::vector<double> t = readArray(series_, timeName, rows, cols, path_);
  hsize_t keep = 0;
  while (keep < rows && t[keep * cols] <= time) ++keep;
  if (keep > 0 && lastKept) *lastKept = t[(keep - 1) * cols];
  for (auto& kv : openSeries_) H5Dclose(kv.second);
  openSeries_.clear();
  H5G_info_t info;
  check(H5Gget_info(series_, &info), path_, "cannot list /series");
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    const std::string name = linkName(series_, k, "/series", path_);
    Handle dset(check(H5Dopen2(series_, name.c_str(), H5P_DEFAULT), path_, "cannot open series " + name), H5Dclose);
    Handle space(H5Dget_space(dset), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > 2) fail(path_, "series " + name + " has rank " + std::to_string(rank) + ", expected 1 or 2");
    hsize_t dims[2] = {0, 1};
    H5Sget_simple_extent_dims(space, dims, nullptr);  // (it writes `rank` values)
    if (dims[0] <= keep) continue;
    dims[0] = keep;
    check(H5Dset_extent(dset, dims), path_, "cannot cut series " + name);
  }
  flush();
  return static_cast<long>(keep);
}

long Hdf5Writer::dropSnapshotsAfter(double time) {
  namespace fs = std::filesystem;
  while (nextSnapshot_ > 0) {
    const std::string name = snapshotName(nextSnapshot_ - 1);
    const fs::path file = fs::path(path_).parent_path() / snapshotFile(nextSnapshot_ - 1);
    double t = std::numeric_limits<double>::infinity();
    if (snapshotFolder_.empty() || fs::exists(file)) {
      Handle g(check(H5Gopen2(snapshots_, name.c_str(), H5P_DEFAULT), path_, "cannot open snapshot " + name),
               H5Gclose);
      readNumberAttribute(g, "time", Numbers::kAny, H5T_NATIVE_DOUBLE, &t, "/snapshots/" + name, path_);
    }
    if (t <= time) break;
    check(H5Ldelete(snapshots_, name.c_str(), H5P_DEFAULT), path_, "cannot drop snapshot " + name);
    if (!snapshotFolder_.empty()) {
      std::error_code ec;
      fs::remove(file, ec);
    }
    --nextSnapshot_;
  }
  flush();
  return nextSnapshot_;
}

void Hdf5Writer::appendScalar(const std::string& name, double value) { appendRow(name, &value, 1, false); }

void Hdf5Writer::appendVector(const std::string& name, const std::vector<double>& values) {
  if (values.empty()) throwParameter("series '" + name + "' record length", 0, "", "at least 1");
  appendRow(name, values.data(), values.size(), true);
}

void Hdf5Writer::appendRow(const std::string& name, const double* values, hsize_t width, bool isVector) {
  if (name.empty() || name.find('/') != std::string::npos) throwParameter("series name", "'" + name + "'", "", "non-empty, without '/'");
  const int rank = isVector ? 2 : 1;
  hid_t dset;
  auto it = openSeries_.find(name);
  if (it != openSeries_.end()) {
    dset = it->second;
  } else if (linkExists(series_, name)) {
    dset = check(H5Dopen2(series_, name.c_str(), H5P_DEFAULT), path_, "cannot open series " + name);
    openSeries_[name] = dset;
  } else {
    hsize_t dims[2] = {0, width};
    hsize_t maxdims[2] = {H5S_UNLIMITED, width};
    hsize_t chunk[2] = {std::max<hsize_t>(1, 4096 / width), width};
    Handle space(H5Screate_simple(rank, dims, maxdims), H5Sclose);
    Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_chunk(dcpl, rank, chunk);
    dset = check(H5Dcreate2(series_, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), path_,
                 "cannot create series " + name);
    openSeries_[name] = dset;
  }
  hsize_t dims[2] = {0, 1};
  {
    Handle space(H5Dget_space(dset), H5Sclose);
    const int r = H5Sget_simple_extent_ndims(space);
    if (r < 1 || r > 2) fail(path_, "series " + name + " has rank " + std::to_string(r) + ", expected 1 or 2");
    H5Sget_simple_extent_dims(space, dims, nullptr);  // (it writes `r` values)
    const hsize_t existingWidth = r == 2 ? dims[1] : 1;
    if (r != rank || existingWidth != width) {
      const std::string expected =
          r == 2 ? "a vector of length " + std::to_string(existingWidth) : std::string("a scalar (appendScalar)");
      throwParameter("series '" + name + "' record", isVector ? "vector of length " + std::to_string(width) : "scalar",
                     "", expected + ", like the series' first record");
    }
  }
  hsize_t newDims[2] = {dims[0] + 1, width};
  check(H5Dset_extent(dset, newDims), path_, "cannot extend series " + name);
  Handle fspace(H5Dget_space(dset), H5Sclose);
  hsize_t start[2] = {dims[0], 0};
  hsize_t count[2] = {1, width};
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, count, nullptr);
  Handle mspace(H5Screate_simple(rank, count, nullptr), H5Sclose);
  check(H5Dwrite(dset, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, values), path_, "cannot append to series " + name);
  flush();
}

std::vector<double> Hdf5Writer::series(const std::string& name, std::size_t* width) const {
  std::size_t rows = 0, cols = 1;
  std::vector<double> values = linkExists(series_, name) ? readArray(series_, name, rows, cols, path_)
                                                         : std::vector<double>();
  if (width) *width = cols;
  return values;
}

long Hdf5Writer::seriesLength(const std::string& name) const {
  if (!linkExists(series_, name)) return 0;
  Handle dset(H5Dopen2(series_, name.c_str(), H5P_DEFAULT), H5Dclose);
  Handle space(H5Dget_space(dset), H5Sclose);
  hsize_t dims[H5S_MAX_RANK] = {0};  // whatever the rank of a dataset someone else put there
  H5Sget_simple_extent_dims(space, dims, nullptr);
  return static_cast<long>(dims[0]);
}

long Hdf5Writer::writeSnapshot(const mpm::ParticleSet& p, double time, long step) {
  mpm::WholeParticleSet whole(p);
  return writeSnapshot(whole, time, step);
}

namespace {

using mpm::ColumnKind;
using mpm::kParticleColumns;

// Writes (or reads) rows [first, first + count) of the dataset of a column from (into) data, values
// of memType.
void transferRows(hid_t dset, const mpm::ParticleColumn& c, hsize_t first, hsize_t count, hid_t memType,
                  const void* in, void* out, const std::string& path) {
  const hsize_t start[2] = {first, 0}, size[2] = {count, c.values};
  Handle fileSpace(H5Dget_space(dset), H5Sclose);
  check(H5Sselect_hyperslab(fileSpace, H5S_SELECT_SET, start, nullptr, size, nullptr), path,
        std::string("cannot select rows of ") + c.name);
  Handle memSpace(check(H5Screate_simple(c.values == 1 ? 1 : 2, size, nullptr), path, "memory dataspace"), H5Sclose);
  if (in)
    check(H5Dwrite(dset, memType, memSpace, fileSpace, H5P_DEFAULT, in), path, std::string("cannot write ") + c.name);
  else
    check(H5Dread(dset, memType, memSpace, fileSpace, H5P_DEFAULT, out), path,
          std::string("cannot read dataset ") + c.name);
}

// A snapshot's datasets and its time and step attributes, written into `loc` (a group, or a
// snapshot file's root) slice by slice.
void writeSnapshotArrays(hid_t loc, mpm::ParticleSlices& particles, double time, long step, const std::string& path) {
  const std::size_t n = particles.size();
  std::vector<std::unique_ptr<Handle>> sets;
  for (const mpm::ParticleColumn& c : kParticleColumns) {
    const hsize_t dims[2] = {n, c.values};
    Handle space(check(H5Screate_simple(c.values == 1 ? 1 : 2, dims, nullptr), path,
                       std::string("dataspace for ") + c.name),
                 H5Sclose);
    const hid_t fileType = c.kind == ColumnKind::kPhase ? H5T_STD_U8LE : H5T_IEEE_F64LE;
    sets.push_back(std::make_unique<Handle>(
        check(H5Dcreate2(loc, c.name, fileType, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), path,
              std::string("cannot create dataset ") + c.name),
        H5Dclose));
  }
  std::vector<double> density;
  mpm::forEachSlice(particles, [&](std::size_t first, const mpm::ParticleSet& p) {
    p.validateSizes(false);
    const std::size_t count = p.size();
    density.resize(count);
    for (std::size_t i = 0; i < count; ++i) density[i] = p.density(i);
    for (std::size_t k = 0; k < sets.size(); ++k) {
      const mpm::ParticleColumn& c = kParticleColumns[k];
      const void* data = c.kind == ColumnKind::kState   ? static_cast<const void*>((p.*c.member).data())
                         : c.kind == ColumnKind::kPhase ? static_cast<const void*>(p.phase.data())
                                                            : density.data();
      transferRows(*sets[k], c, first, count, c.kind == ColumnKind::kPhase ? H5T_NATIVE_UINT8 : H5T_NATIVE_DOUBLE,
                   data, nullptr, path);
    }
  });
  writeDoubleAttribute(loc, "time", time, path);
  writeLongAttribute(loc, "step", step, path);
}

}  // namespace

long Hdf5Writer::writeSnapshot(mpm::ParticleSlices& particles, double time, long step) {
  const long index = nextSnapshot_;
  const std::string name = snapshotName(index);
  if (snapshotFolder_.empty()) {
    if (linkExists(snapshots_, kIncomplete)) H5Ldelete(snapshots_, kIncomplete, H5P_DEFAULT);
    {
      Handle g(check(H5Gcreate2(snapshots_, kIncomplete, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), path_,
                     "cannot create snapshot group"),
               H5Gclose);
      writeSnapshotArrays(g, particles, time, step, path_);
    }
    flush();
    check(H5Lmove(snapshots_, kIncomplete, snapshots_, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), path_,
          "cannot name snapshot " + name);
  } else {
    const std::string file = (std::filesystem::path(path_).parent_path() / snapshotFile(index)).string();
    const std::string part = file + ".part";
    {
      Handle fapl(fileAccessWithoutLocking(), H5Pclose);
      Handle f(check(H5Fcreate(part.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), part, "cannot create"), H5Fclose);
      writeSnapshotArrays(f, particles, time, step, part);
    }
    std::error_code ec;
    std::filesystem::rename(part, file, ec);
    if (ec) fail(file, "cannot rename the finished snapshot " + part + ": " + ec.message());
    check(H5Lcreate_external(snapshotFile(index).c_str(), "/", snapshots_, name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
          path_, "cannot link snapshot " + name);
  }
  flush();
  ++nextSnapshot_;
  return index;
}

// ------------------------------------------------------------------------------ readers

std::vector<double> readSeries(const std::string& path, const std::string& name, std::size_t* width) {
  Handle file = openForReading(path);
  if (!linkExists(file, "series")) fail(path, "no group /series");
  Handle g(check(H5Gopen2(file, "series", H5P_DEFAULT), path, "cannot open /series as a group"), H5Gclose);
  std::size_t rows = 0, cols = 0;
  auto out = readArray(g, name, rows, cols, path);
  if (width) *width = cols;
  return out;
}

long readNumSnapshots(const std::string& path) {
  Handle file = openForReading(path);
  if (!linkExists(file, "snapshots")) return 0;
  Handle g(check(H5Gopen2(file, "snapshots", H5P_DEFAULT), path, "cannot open /snapshots as a group"), H5Gclose);
  long n = 0;
  while (linkExists(g, snapshotName(n))) ++n;
  return n;
}

void readSnapshot(const std::string& path, long index, mpm::ParticleSet& out, double* time, long* step) {
  SnapshotSlices snapshot(path, index, std::numeric_limits<std::size_t>::max());
  out = snapshot.slice(0, snapshot.size());
  if (time) *time = snapshot.time();
  if (step) *step = snapshot.step();
}

SnapshotSlices::SnapshotSlices(const std::string& path, long index, std::size_t sliceSize)
    : path_(path), group_("snapshots/" + snapshotName(index)), sliceSize_(sliceSize) {
  if (sliceSize == 0) throwParameter("sliceSize", 0, "particles", ">= 1");
  Handle file = openForReading(path);
  if (!linkExists(file, "snapshots") || !linkExists(file, group_)) fail(path, "no snapshot /" + group_);
  Handle g(check(H5Gopen2(file, group_.c_str(), H5P_DEFAULT), path, "cannot open /" + group_), H5Gclose);
  const std::string where = "/" + group_;
  const char* firstName = nullptr;
  for (const mpm::ParticleColumn& c : kParticleColumns) {
    if (c.kind == ColumnKind::kDensity) continue;
    const std::string what = "dataset " + std::string(c.name) + " of " + where;
    if (!linkExists(g, c.name)) fail(path, "no dataset " + std::string(c.name) + " in " + where);
    Handle dset(check(H5Dopen2(g, c.name, H5P_DEFAULT), path, "cannot open " + what), H5Dclose);
    const Numbers numbers = c.kind == ColumnKind::kPhase ? Numbers::kIntegers : Numbers::kAny;
    const auto extent = checkedExtent(dset, numbers, what, path);
    if (extent.second != c.values)
      fail(path, what + " has " + std::to_string(extent.second) + " values a particle, expected " +
                     std::to_string(c.values));
    if (firstName && extent.first != n_)
      fail(path, "snapshot " + where + " has arrays of inconsistent length: " + firstName + " has " +
                     std::to_string(n_) + " particles, " + c.name + " " + std::to_string(extent.first));
    n_ = extent.first;
    if (!firstName) firstName = c.name;
  }
  // What a restart sets the solver's clock to.
  readNumberAttribute(g, "time", Numbers::kAny, H5T_NATIVE_DOUBLE, &time_, where, path);
  if (!std::isfinite(time_) || time_ < 0) {
    std::ostringstream os;
    os << "attribute time of " << where << " = " << time_ << " s: must be finite and >= 0";
    fail(path, os.str());
  }
  long long step = 0;
  readNumberAttribute(g, "step", Numbers::kIntegers, H5T_NATIVE_LLONG, &step, where, path);
  if (step < 0) fail(path, "attribute step of " + where + " = " + std::to_string(step) + ": must be >= 0");
  step_ = static_cast<long>(step);
  // Valid: keep the file and the group open for the slices (an extra reference outlives the
  // handles, which close theirs on any failure above).
  H5Iinc_ref(file);
  H5Iinc_ref(g);
  file_ = file;
  snapshot_ = g;
}

SnapshotSlices::~SnapshotSlices() {
  H5Gclose(snapshot_);
  H5Fclose(file_);
}

const mpm::ParticleSet& SnapshotSlices::slice(std::size_t first, std::size_t count) {
  mpm::validateSliceRange("snapshot slice", first, count, n_, " of /" + group_ + " in " + path_);
  mpm::ParticleSet& p = buffer_;
  for (const mpm::ParticleColumn& c : kParticleColumns) {
    if (c.kind == ColumnKind::kDensity) continue;
    if (c.kind == ColumnKind::kState)
      (p.*c.member).resize(count * c.values);
    else
      p.phase.resize(count);
    if (count == 0) continue;
    Handle dset(check(H5Dopen2(snapshot_, c.name, H5P_DEFAULT), path_, std::string("cannot open dataset ") + c.name),
                H5Dclose);
    if (c.kind == ColumnKind::kState) {
      transferRows(dset, c, first, count, H5T_NATIVE_DOUBLE, nullptr, (p.*c.member).data(), path_);
      continue;
    }
    // The phase is read wide: HDF5 would clip -1 or 256 into the uint8 range without a word.
    phase_.resize(count);
    transferRows(dset, c, first, count, H5T_NATIVE_LLONG, nullptr, phase_.data(), path_);
    for (std::size_t i = 0; i < count; ++i) {
      if (phase_[i] < 0 || phase_[i] > 2)
        fail(path_, "dataset phase of /" + group_ + ": particle " + std::to_string(first + i) + " has phase " +
                        std::to_string(phase_[i]) + ", expected 0 (elastic), 1 (flowing) or 2 (gasified)");
      p.phase[i] = static_cast<std::uint8_t>(phase_[i]);
    }
  }
  p.fext.assign(3 * count, 0.0);
  return p;
}

void writeMpmHeader(Hdf5Writer& w, const std::string& sceneJson, const mpm::MpmParams& params,
                    const std::string& solverName) {
  w.setAttribute("parameters", sceneJson);
  w.setAttribute("units", "SI: m, kg, s, Pa; stress tension positive, components xx yy zz yz xz xy");
  w.setAttribute("solver", solverName);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const mpm::FlipBlend& blend = params.flip;
  const double step = blend.rateStep();  // unless per step, the rate is the same at any step
  // the blend's parameters under their scene keys; the damping rate is derived, not a key
  const auto key = [](const char* k) -> std::string { return mpm::sceneParameter(k).key; };
  w.setAttribute(key("flip_viscosity"), blend.perStep() ? nan : blend.viscosityFor(step, params.dx));
  w.setAttribute("flip_damping_rate", blend.perStep() ? nan : blend.dampingRate(step, params.dx));
  w.setAttribute(key("flip_alpha"), blend.setAlpha());
  w.setAttribute(key("flip_reference_dt"), blend.perStep() ? 0.0 : blend.referenceDt());
  w.setAttribute("flip_blend", blend.describe(params.dx));
}

std::optional<std::string> readOptionalStringAttribute(const std::string& path, const std::string& name) {
  Handle file = openForReading(path);
  const std::string what = "root attribute " + name;
  const htri_t exists = H5Aexists(file, name.c_str());
  if (exists == 0) return std::nullopt;
  if (exists < 0) fail(path, "cannot look up " + what);
  Handle a(check(H5Aopen(file, name.c_str(), H5P_DEFAULT), path, "cannot open " + what), H5Aclose);
  Handle type(check(H5Aget_type(a), path, "cannot read the type of " + what), H5Tclose);
  const H5T_class_t c = H5Tget_class(type);
  if (c != H5T_STRING) fail(path, what + " holds " + typeClassName(c) + ", expected a string");
  Handle space(check(H5Aget_space(a), path, "cannot read the shape of " + what), H5Sclose);
  const hssize_t count = H5Sget_simple_extent_npoints(space);
  // (HDF5 writes every string of an array attribute where one is asked for)
  if (count != 1) fail(path, what + " holds " + std::to_string(count) + " strings, expected one");
  // Read as stored (its own type: HDF5 converts neither between variable and fixed length nor
  // between ASCII and UTF-8).
  if (H5Tis_variable_str(type) > 0) {
    char* s = nullptr;
    check(H5Aread(a, type, &s), path, "cannot read " + what);
    std::string out = s ? s : "";
    H5Dvlen_reclaim(type, space, H5P_DEFAULT, &s);
    return out;
  }
  std::string out(H5Tget_size(type), '\0');
  check(H5Aread(a, type, out.data()), path, "cannot read " + what);
  out.resize(std::strlen(out.c_str()));  // (a fixed-length string is padded with NULs, or ends with one)
  return out;
}

std::string readStringAttribute(const std::string& path, const std::string& name) {
  std::optional<std::string> value = readOptionalStringAttribute(path, name);
  if (!value) fail(path, "no root attribute " + name);
  return *value;
}

}  // namespace io
}  // namespace mpmsdem
