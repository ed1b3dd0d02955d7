// Append-only HDF5 output of an MPM run (HDF5 C API; readable with h5py).
//
// File layout:
//   /                      root attributes set with setAttribute(): e.g. "units" (string),
//                          "parameters" (the scene as a JSON string), "solver" (string)
//   /series/<name>         extendible datasets, one record per appendScalar()/appendVector()
//                          call: float64 shape (records,) for scalars, (records, k) for vectors
//   /snapshots/<NNNNNN>/   one group per writeSnapshot() call, NNNNNN = snapshot index
//                          (0-based, zero-padded to 6 digits), attributes "time" [s] and
//                          "step"; datasets (N = particle count):
//                            x (N,3) [m], v (N,3) [m/s], stress (N,6) [Pa] (xx yy zz yz xz xy,
//                            tension positive), density (N) [kg/m^3] = mass/(J volume0),
//                            phase (N) uint8 (0 elastic, 1 flowing, 2 gasified),
//                            gammaDotP (N) [1/s], mass (N) [kg], volume0 (N) [m^3], J (N) [-]
//                          (mass, volume0 and J make a snapshot a complete restart state).
//                          With snapshot files (run outputs), each snapshot is a file of its
//                          own, <name>.snapshots/NNNNNN.h5, holding that group's attributes and
//                          datasets at its root, and /snapshots/NNNNNN is an external link to
//                          it: h5py and the readers below follow it as if it were the group.
//
// Every record is followed by H5Fflush, so a run killed between two records leaves a file
// whose every record written so far can be read. A run killed *during* a flush can leave the
// file unreadable: HDF5 rewrites its metadata in place, in several writes. commit() is the
// guard for restarts: it copies the flushed file to <file>.restart (a temporary name renamed,
// so the copy is always whole), and resumeFromCommit() puts that copy back before a restart
// appends. Snapshot files are written under a temporary name and renamed, so they are whole or
// absent; keeping them out of the main file keeps that file, and each commit's copy, small.
// The writer disables HDF5's file locking, so h5py can open the file (read-only) while the
// run is still writing.
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace io {

// For a program that owns every HDF5 file it opens (the driver): call before any other HDF5
// call. HDF5's own clean-up at exit closes the files left open, and crashes (SIGSEGV) on a file
// whose close failed because its last write did (a full disk); the writers here close their
// files themselves, so that clean-up has nothing to do and is turned off. Not for a process
// whose HDF5 library other code shares (h5py in YADE's Python).
void skipHdf5CleanupAtExit();

class Hdf5Writer {
 public:
  // Truncate: create the file (replacing an existing one, its restart copy and its snapshot
  // files). Append: open an existing file and continue its series and snapshot numbering
  // (restart: call resumeFromCommit first); creates it when absent.
  enum class Mode { Truncate, Append };

  // snapshotFiles: false keeps every snapshot a group inside the file (a checkpoint file);
  // true writes each as a file of its own in snapshotFolder(path) (run outputs). Throws
  // RuntimeFailure when the file cannot be created or opened (names the path).
  explicit Hdf5Writer(const std::string& path, Mode mode = Mode::Truncate, bool snapshotFiles = false);
  ~Hdf5Writer();
  Hdf5Writer(const Hdf5Writer&) = delete;
  Hdf5Writer& operator=(const Hdf5Writer&) = delete;

  const std::string& path() const { return path_; }

  // Root attribute (replaced when it exists): a UTF-8 string or a float64.
  void setAttribute(const std::string& name, const std::string& value);
  void setAttribute(const std::string& name, double value);

  // Append one record to /series/<name>, creating the dataset on first use. A vector
  // series keeps the width of its first record; another width throws ParameterError.
  void appendScalar(const std::string& name, double value);
  void appendVector(const std::string& name, const std::vector<double>& values);

  // Write /snapshots/<index>/ for the particles; returns the snapshot index used. The second
  // form reads them slice by slice (a slice of the set on the host at a time), same file.
  long writeSnapshot(const mpm::ParticleSet& particles, double time, long step);
  long writeSnapshot(mpm::ParticleSlices& particles, double time, long step);

  // Restart from a checkpoint taken before the file's end: keep the records of /series/*
  // whose /series/<timeName> value is <= time, drop the later ones (every series is cut to
  // that many records, so series recorded together stay aligned) and return how many were
  // kept (0 when there is no <timeName> series); `lastKept` receives the time of the last
  // record kept (unchanged when none is). The file then holds no record after the
  // checkpoint, so the continued run appends without duplicates or steps back in time.
  long truncateSeriesAfter(const std::string& timeName, double time, double* lastKept = nullptr);
  // The same for /snapshots: drop the numbered snapshots whose `time` attribute is later than
  // `time` (numbering continues after the last one kept), with their files; returns how many
  // are kept. A last snapshot whose file is gone was dropped by an earlier restart that was
  // killed before its next commit: it is dropped again.
  long dropSnapshotsAfter(double time);

  // The file as it is now becomes what a restart goes back to: flushed and copied to
  // restartCopyPath(path()), whole (written under a temporary name, then renamed). Call it
  // where a run takes a checkpoint, before the checkpoint itself is written.
  void commit();

  // Number of records in /series/<name> (0 when absent) and of snapshots in the file.
  long seriesLength(const std::string& name) const;
  // /series/<name> as it is in the open file, flat row-major (empty when absent); `width`
  // receives the record width. A restart reads the records it continues from with it.
  std::vector<double> series(const std::string& name, std::size_t* width = nullptr) const;
  long numSnapshots() const { return nextSnapshot_; }

 private:
  void appendRow(const std::string& name, const double* values, hsize_t width, bool isVector);
  void flush();
  void close();  // what is open (the destructor's work, and a constructor's that throws)
  std::string snapshotFile(long index) const;  // relative to the file's directory

  std::string path_;
  std::string snapshotFolder_;
  hid_t file_ = -1;
  hid_t series_ = -1;
  hid_t snapshots_ = -1;
  std::map<std::string, hid_t> openSeries_;  // series datasets kept open between appends
  long nextSnapshot_ = 0;
};

// The folder of a file's snapshot files, beside it: <name without .h5>.snapshots (mpm.h5:
// mpm.snapshots/), and the name its links use (relative to the file's directory).
std::string snapshotFolder(const std::string& path);
// <path>.restart: the copy commit() keeps.
std::string restartCopyPath(const std::string& path);
// Before a restart appends to `path`: put the copy of its last commit() back in its place (the
// records written after that commit belong to the killed run and are dropped by the restart
// anyway; the file itself may be damaged). Returns false, leaving `path` alone, when there is
// no copy (no commit yet, or a file of a version without commits).
bool resumeFromCommit(const std::string& path);

// The root attributes of an MPM output or checkpoint: "parameters" (the scene JSON), "units",
// "solver", and the FLIP/PIC blend it ran with (the damping per second is a model quantity,
// docs/physics.md): "flip_viscosity" [m^2/s] and "flip_damping_rate" [1/s] (NaN per step: they
// then follow the step, see /series/dt), "flip_alpha" and "flip_reference_dt" [s] (0: per step;
// both NaN when a viscosity set the blend) and "flip_blend" (mpm::FlipBlend::describe).
void writeMpmHeader(Hdf5Writer& w, const std::string& sceneJson, const mpm::MpmParams& params,
                    const std::string& solverName);

// Readers (used for restart and by tests). All throw RuntimeFailure naming the path and
// the object when the file or the object does not exist.

// Whole /series/<name> as a flat row-major array; `width` receives the record width
// (1 for scalar series).
std::vector<double> readSeries(const std::string& path, const std::string& name, std::size_t* width = nullptr);
// Number of snapshot groups in the file.
long readNumSnapshots(const std::string& path);
// Snapshot `index` into `out` (x, v, stress, mass, volume0, J, gammaDotP, phase; fext is
// resized to zeros); `time` and `step` receive its attributes when non-null. SnapshotSlices
// below reads the same a slice at a time.
void readSnapshot(const std::string& path, long index, mpm::ParticleSet& out, double* time = nullptr,
                  long* step = nullptr);
// Root string attribute `name` (variable or fixed length, ASCII or UTF-8).
std::string readStringAttribute(const std::string& path, const std::string& name);
// The same, or nothing when the file has no attribute `name`; one there that is not a single
// string (a number, an array of strings) is a RuntimeFailure naming it.
std::optional<std::string> readOptionalStringAttribute(const std::string& path, const std::string& name);

// Snapshot `index` read slice by slice (what readSnapshot reads, a slice at a time on the
// host): MpmSolver::setParticles(ParticleSlices&) loads a restart this way. The file stays
// open while the object lives.
class SnapshotSlices : public mpm::ParticleSlices {
 public:
  SnapshotSlices(const std::string& path, long index, std::size_t sliceSize = 1 << 16);
  ~SnapshotSlices();
  SnapshotSlices(const SnapshotSlices&) = delete;
  SnapshotSlices& operator=(const SnapshotSlices&) = delete;
  std::size_t size() const override { return n_; }
  std::size_t sliceSize() const override { return sliceSize_; }
  const mpm::ParticleSet& slice(std::size_t first, std::size_t count) override;
  double time() const { return time_; }  // the snapshot's `time` attribute [s]
  long step() const { return step_; }     // its `step` attribute

 private:
  std::string path_, group_;
  hid_t file_ = -1, snapshot_ = -1;
  std::size_t n_ = 0, sliceSize_;
  double time_ = 0;
  long step_ = 0;
  mpm::ParticleSet buffer_;
  std::vector<long long> phase_;  // a slice's phases as read, before their range is checked
};

}  // namespace io
}  // namespace mpmsdem
