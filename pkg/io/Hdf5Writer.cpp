#include "io/Hdf5Writer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include "common/Error.hpp"
#include "mpm/MpmScene.hpp"

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
  if (linkExists(file, name)) return check(H5Gopen2(file, name.c_str(), H5P_DEFAULT), path, "cannot open group " + name);
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

// Read a whole dataset of `memType` elements; `rows`/`cols` receive its shape.
template <typename T>
std::vector<T> readArray(hid_t loc, const std::string& name, hid_t memType, std::size_t& rows, std::size_t& cols,
                         const std::string& path) {
  if (!linkExists(loc, name)) fail(path, "no dataset " + name);
  Handle dset(check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), path, "cannot open dataset " + name), H5Dclose);
  Handle space(H5Dget_space(dset), H5Sclose);
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 2) fail(path, "dataset " + name + " has rank " + std::to_string(rank) + ", expected 1 or 2");
  H5Sget_simple_extent_dims(space, dims, nullptr);
  rows = dims[0];
  cols = rank == 2 ? dims[1] : 1;
  std::vector<T> out(rows * cols);
  if (!out.empty())
    check(H5Dread(dset, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), path, "cannot read dataset " + name);
  return out;
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
  if (mode == Mode::Append && fs::exists(path)) {
    file_ = check(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl), path, "cannot open for appending");
    if (snapshotFiles && fs::is_directory(folder))  // snapshots a killed run left half-written
      for (const auto& entry : fs::directory_iterator(folder))
        if (entry.path().extension() == ".part") fs::remove(entry.path(), ec);
  } else {
    // a new run: nothing of an earlier one in this place may be restored or linked later
    fs::remove(restartCopyPath(path), ec);
    if (snapshotFiles) fs::remove_all(folder, ec);
    file_ = check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), path, "cannot create");
  }
  if (snapshotFiles) {
    fs::create_directories(folder, ec);
    if (ec) fail(path, "cannot create the snapshot folder " + folder.string() + ": " + ec.message());
  }
  series_ = openOrCreateGroup(file_, "series", path);
  snapshots_ = openOrCreateGroup(file_, "snapshots", path);
  if (linkExists(snapshots_, kIncomplete)) H5Ldelete(snapshots_, kIncomplete, H5P_DEFAULT);
  while (linkExists(snapshots_, snapshotName(nextSnapshot_))) ++nextSnapshot_;
  flush();
}

Hdf5Writer::~Hdf5Writer() {
  for (auto& kv : openSeries_) H5Dclose(kv.second);
  if (snapshots_ >= 0) H5Gclose(snapshots_);
  if (series_ >= 0) H5Gclose(series_);
  if (file_ >= 0) H5Fclose(file_);
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
  const std::vector<double> t = readArray<double>(series_, timeName, H5T_NATIVE_DOUBLE, rows, cols, path_);
  hsize_t keep = 0;
  while (keep < rows && t[keep * cols] <= time) ++keep;
  if (keep > 0 && lastKept) *lastKept = t[(keep - 1) * cols];
  for (auto& kv : openSeries_) H5Dclose(kv.second);
  openSeries_.clear();
  H5G_info_t info;
  check(H5Gget_info(series_, &info), path_, "cannot list /series");
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    char name[256];
    if (H5Lget_name_by_idx(series_, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT) < 0) continue;
    Handle dset(check(H5Dopen2(series_, name, H5P_DEFAULT), path_, std::string("cannot open series ") + name),
                H5Dclose);
    Handle space(H5Dget_space(dset), H5Sclose);
    hsize_t dims[2] = {0, 1};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    if (dims[0] <= keep) continue;
    dims[0] = keep;
    check(H5Dset_extent(dset, dims), path_, std::string("cannot cut series ") + name);
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
      Handle a(check(H5Aopen(g, "time", H5P_DEFAULT), path_, "no attribute time in snapshot " + name), H5Aclose);
      check(H5Aread(a, H5T_NATIVE_DOUBLE, &t), path_, "cannot read the time of snapshot " + name);
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
    H5Sget_simple_extent_dims(space, dims, nullptr);
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

long Hdf5Writer::seriesLength(const std::string& name) const {
  if (!linkExists(series_, name)) return 0;
  Handle dset(H5Dopen2(series_, name.c_str(), H5P_DEFAULT), H5Dclose);
  Handle space(H5Dget_space(dset), H5Sclose);
  hsize_t dims[2] = {0, 0};
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

// Writes (or reads) rows [first, first + count) of the dataset of a column from (into) data.
void transferRows(hid_t dset, const mpm::ParticleColumn& c, hsize_t first, hsize_t count, const void* in, void* out,
                  const std::string& path) {
  const hid_t memType = c.kind == ColumnKind::kPhase ? H5T_NATIVE_UINT8 : H5T_NATIVE_DOUBLE;
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
      transferRows(*sets[k], c, first, count, data, nullptr, path);
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
  Handle g(H5Gopen2(file, "series", H5P_DEFAULT), H5Gclose);
  std::size_t rows = 0, cols = 0;
  auto out = readArray<double>(g, name, H5T_NATIVE_DOUBLE, rows, cols, path);
  if (width) *width = cols;
  return out;
}

long readNumSnapshots(const std::string& path) {
  Handle file = openForReading(path);
  if (!linkExists(file, "snapshots")) return 0;
  Handle g(H5Gopen2(file, "snapshots", H5P_DEFAULT), H5Gclose);
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
  bool first = true;
  for (const mpm::ParticleColumn& c : kParticleColumns) {
    if (c.kind == ColumnKind::kDensity) continue;
    if (!linkExists(g, c.name)) fail(path, "no dataset " + std::string(c.name) + " in /" + group_);
    Handle dset(check(H5Dopen2(g, c.name, H5P_DEFAULT), path, std::string("cannot open dataset ") + c.name),
                H5Dclose);
    Handle space(H5Dget_space(dset), H5Sclose);
    hsize_t dims[2] = {0, 1};
    const int rank = H5Sget_simple_extent_ndims(space);
    H5Sget_simple_extent_dims(space, dims, nullptr);
    const hsize_t width = rank == 2 ? dims[1] : 1;
    if (rank < 1 || rank > 2 || width != c.values || (!first && dims[0] != n_))
      fail(path, "snapshot /" + group_ + " has arrays of inconsistent length");
    n_ = dims[0];
    first = false;
  }
  {
    Handle a(check(H5Aopen(g, "time", H5P_DEFAULT), path, "no attribute time in /" + group_), H5Aclose);
    H5Aread(a, H5T_NATIVE_DOUBLE, &time_);
  }
  {
    Handle a(check(H5Aopen(g, "step", H5P_DEFAULT), path, "no attribute step in /" + group_), H5Aclose);
    long long s = 0;
    H5Aread(a, H5T_NATIVE_LLONG, &s);
    step_ = static_cast<long>(s);
  }
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
    void* data;
    if (c.kind == ColumnKind::kState) {
      (p.*c.member).resize(count * c.values);
      data = (p.*c.member).data();
    } else {
      p.phase.resize(count);
      data = p.phase.data();
    }
    if (count == 0) continue;
    Handle dset(check(H5Dopen2(snapshot_, c.name, H5P_DEFAULT), path_, std::string("cannot open dataset ") + c.name),
                H5Dclose);
    transferRows(dset, c, first, count, nullptr, data, path_);
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
  const bool viscosity = params.flipViscosity > 0, perStep = params.flipBlendPerStep();
  const double unit = viscosity ? 1.0 : params.flipReferenceDt;  // unless per step, the rate is the same at any step
  w.setAttribute("flip_viscosity", perStep ? nan : params.flipViscosityFor(unit));
  w.setAttribute("flip_damping_rate", perStep ? nan : params.flipDampingRate(unit));
  w.setAttribute("flip_alpha", viscosity ? nan : params.flipAlpha);
  w.setAttribute("flip_reference_dt", viscosity ? nan : params.flipReferenceDt);
  w.setAttribute("flip_blend", mpm::describeFlipBlend(params));
}

std::string readStringAttribute(const std::string& path, const std::string& name) {
  Handle file = openForReading(path);
  if (H5Aexists(file, name.c_str()) <= 0) fail(path, "no root attribute " + name);
  Handle a(H5Aopen(file, name.c_str(), H5P_DEFAULT), H5Aclose);
  Handle type(utf8StringType(), H5Tclose);
  char* s = nullptr;
  check(H5Aread(a, type, &s), path, "cannot read attribute " + name + " as a string");
  std::string out = s ? s : "";
  Handle space(H5Aget_space(a), H5Sclose);
  H5Dvlen_reclaim(type, space, H5P_DEFAULT, &s);
  return out;
}

}  // namespace io
}  // namespace mpmsdem
