// HDF5 and VTK writers: exact read-back, append across reopen, validity of the file on disk
// after every flush (what a killed run leaves), VTK/PVD parse-back.
#include <gtest/gtest.h>
#ifdef MPMSDEM_WITH_HDF5
#include <hdf5.h>
#endif

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <unistd.h>

#include "common/Error.hpp"
#ifdef MPMSDEM_WITH_HDF5
#include "io/Hdf5Writer.hpp"
#endif
#include "io/VtkWriter.hpp"

using namespace mpmsdem;
using namespace mpmsdem::io;
namespace fs = std::filesystem;

namespace {

fs::path scratchDir() { return fs::temp_directory_path() / ("mpmsdem_test_io_" + std::to_string(::getpid())); }

// Removes the scratch folder after the last test.
struct ScratchCleanup : ::testing::Environment {
  void TearDown() override { fs::remove_all(scratchDir()); }
};
::testing::Environment* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

fs::path scratch(const std::string& name) {
  const fs::path dir = scratchDir();
  fs::create_directories(dir);
  const fs::path p = dir / name;
  fs::remove(p);
  return p;
}

// An empty folder of the scratch folder (snapshot files and restart copies go beside a file).
fs::path freshFolder(const std::string& name) {
  const fs::path dir = scratchDir() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// n particles with distinct, non-round values in every field.
mpm::ParticleSet makeParticles(std::size_t n) {
  mpm::ParticleSet p;
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      p.x.push_back(0.1 * i + 0.01 * a + 1.0 / 3.0);
      p.v.push_back(-0.7 * i + 0.3 * a + 1e-3 / 7.0);
      p.fext.push_back(0.0);
    }
    for (int k = 0; k < 6; ++k) p.stress.push_back(-1000.0 * (i + 1) - 17.0 * k + 0.125);
    p.mass.push_back(1.6e-4 * (1 + 0.01 * i));
    p.volume0.push_back(1e-7 * (1 + 0.02 * i));
    p.J.push_back(1.0 + 1e-3 * i);
    p.gammaDotP.push_back(0.5 * i + 1.0 / 9.0);
    p.phase.push_back(static_cast<std::uint8_t>(i % 3));
  }
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream is(p, std::ios::binary);
  std::stringstream ss;
  ss << is.rdbuf();
  return ss.str();
}

// Values of the ascii DataArray `name` in a .vtp text.
std::vector<double> asciiArray(const std::string& text, const std::string& name) {
  const std::string tag = "Name=\"" + name + "\"";
  const std::size_t at = text.find(tag);
  if (at == std::string::npos) return {};
  const std::size_t begin = text.find('>', at) + 1;
  const std::size_t end = text.find("</DataArray>", begin);
  std::istringstream is(text.substr(begin, end - begin));
  std::vector<double> out;
  double d;
  while (is >> d) out.push_back(d);
  return out;
}

// Float32 values of the appended DataArray `name` (raw encoding, UInt64 headers).
std::vector<float> rawFloatArray(const std::string& text, const std::string& name) {
  const std::size_t at = text.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const std::size_t off = text.find("offset=\"", at) + 8;
  const std::size_t offset = std::stoul(text.substr(off, text.find('"', off) - off));
  const std::size_t base = text.find('_', text.find("<AppendedData")) + 1;
  std::uint64_t nbytes;
  std::memcpy(&nbytes, &text[base + offset], 8);
  std::vector<float> out(nbytes / 4);
  std::memcpy(out.data(), &text[base + offset + 8], nbytes);
  return out;
}

int intAttribute(const std::string& text, const std::string& attr) {
  const std::regex re(attr + "=\"([0-9]+)\"");
  std::smatch m;
  if (!std::regex_search(text, m, re)) return -1;
  return std::stoi(m[1].str());
}

}  // namespace

#ifdef MPMSDEM_WITH_HDF5  // an MPM-only build may lack HDF5 (CMakeLists.txt)
TEST(Hdf5Writer, WritesAndReadsBackExactValues) {
  const fs::path path = scratch("exact.h5");
  const auto p = makeParticles(7);
  {
    Hdf5Writer w(path.string());
    w.setAttribute("units", "SI");
    w.setAttribute("parameters", std::string("{\"dx\": 0.01, \"name\": \"d\u00e9bris\"}"));
    w.setAttribute("gravity", -9.81);
    for (int k = 0; k < 5; ++k) {
      w.appendScalar("time", 0.1 * k + 1.0 / 3.0);
      w.appendVector("com", {1.0 * k, 2.0 / 3.0, -k / 7.0});
    }
    EXPECT_EQ(w.writeSnapshot(p, 0.25, 42), 0);
    EXPECT_EQ(w.writeSnapshot(p, 0.5, 84), 1);
    EXPECT_EQ(w.seriesLength("time"), 5);
    EXPECT_EQ(w.seriesLength("absent"), 0);
  }
  std::size_t width = 0;
  const auto time = readSeries(path.string(), "time", &width);
  ASSERT_EQ(time.size(), 5u);
  EXPECT_EQ(width, 1u);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(time[k], 0.1 * k + 1.0 / 3.0);
  const auto com = readSeries(path.string(), "com", &width);
  ASSERT_EQ(com.size(), 15u);
  EXPECT_EQ(width, 3u);
  EXPECT_EQ(com[3 * 4 + 0], 4.0);
  EXPECT_EQ(com[3 * 4 + 1], 2.0 / 3.0);
  EXPECT_EQ(com[3 * 4 + 2], -4 / 7.0);
  EXPECT_EQ(readStringAttribute(path.string(), "units"), "SI");
  EXPECT_EQ(readStringAttribute(path.string(), "parameters"), "{\"dx\": 0.01, \"name\": \"d\u00e9bris\"}");

  ASSERT_EQ(readNumSnapshots(path.string()), 2);
  mpm::ParticleSet q;
  double t = 0;
  long step = 0;
  readSnapshot(path.string(), 1, q, &t, &step);
  EXPECT_EQ(t, 0.5);
  EXPECT_EQ(step, 84);
  ASSERT_EQ(q.size(), 7u);
  EXPECT_EQ(q.x, p.x);
  EXPECT_EQ(q.v, p.v);
  EXPECT_EQ(q.stress, p.stress);
  EXPECT_EQ(q.mass, p.mass);
  EXPECT_EQ(q.volume0, p.volume0);
  EXPECT_EQ(q.J, p.J);
  EXPECT_EQ(q.gammaDotP, p.gammaDotP);
  EXPECT_EQ(q.phase, p.phase);
  EXPECT_EQ(q.fext, std::vector<double>(21, 0.0));

  // Shapes and the derived density, read with the plain HDF5 API as a user would.
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  hid_t d = H5Dopen2(f, "/snapshots/000000/stress", H5P_DEFAULT);
  hid_t s = H5Dget_space(d);
  hsize_t dims[2] = {0, 0};
  EXPECT_EQ(H5Sget_simple_extent_ndims(s), 2);
  H5Sget_simple_extent_dims(s, dims, nullptr);
  EXPECT_EQ(dims[0], 7u);
  EXPECT_EQ(dims[1], 6u);
  H5Sclose(s);
  H5Dclose(d);
  d = H5Dopen2(f, "/snapshots/000000/density", H5P_DEFAULT);
  std::vector<double> density(7);
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, density.data());
  H5Dclose(d);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(density[i], p.mass[i] / (p.J[i] * p.volume0[i]), 1e-12 * density[i]);
  EXPECT_NEAR(density[0], 1600.0, 1e-9);
  hid_t a = H5Aopen(f, "gravity", H5P_DEFAULT);
  double g = 0;
  H5Aread(a, H5T_NATIVE_DOUBLE, &g);
  EXPECT_EQ(g, -9.81);
  H5Aclose(a);
  H5Fclose(f);
}

TEST(Hdf5Writer, AppendsAcrossCloseAndReopen) {
  const fs::path path = scratch("append.h5");
  const auto p = makeParticles(3);
  {
    Hdf5Writer w(path.string());
    for (int k = 0; k < 3; ++k) w.appendScalar("time", k);
    w.writeSnapshot(p, 0.0, 0);
  }
  {
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Append);
    EXPECT_EQ(w.numSnapshots(), 1);
    EXPECT_EQ(w.seriesLength("time"), 3);
    for (int k = 3; k < 5; ++k) w.appendScalar("time", k);
    EXPECT_EQ(w.writeSnapshot(p, 1.0, 10), 1);
  }
  const auto time = readSeries(path.string(), "time");
  ASSERT_EQ(time.size(), 5u);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(time[k], double(k));
  EXPECT_EQ(readNumSnapshots(path.string()), 2);
  double t = 0;
  long step = 0;
  mpm::ParticleSet q;
  readSnapshot(path.string(), 1, q, &t, &step);
  EXPECT_EQ(t, 1.0);
  EXPECT_EQ(step, 10);
  // Truncate starts afresh.
  { Hdf5Writer w(path.string(), Hdf5Writer::Mode::Truncate); }
  EXPECT_EQ(readNumSnapshots(path.string()), 0);
  EXPECT_THROW(readSeries(path.string(), "time"), RuntimeFailure);
}

TEST(Hdf5Writer, FileOnDiskIsValidAfterEveryRecord) {
  // Copy the file while the writer still holds it open: the copy is what a killed run leaves.
  const fs::path path = scratch("live.h5");
  const fs::path copy = scratch("live_copy.h5");
  const auto p = makeParticles(4);
  Hdf5Writer w(path.string());
  for (int k = 0; k < 4; ++k) {
    w.appendScalar("kinetic_energy", 0.5 * k);
    w.writeSnapshot(p, 0.1 * k, k);
    fs::copy_file(path, copy, fs::copy_options::overwrite_existing);
    const auto ke = readSeries(copy.string(), "kinetic_energy");
    ASSERT_EQ(ke.size(), std::size_t(k + 1));
    EXPECT_EQ(ke.back(), 0.5 * k);
    ASSERT_EQ(readNumSnapshots(copy.string()), k + 1);
    mpm::ParticleSet q;
    double t = -1;
    readSnapshot(copy.string(), k, q, &t);
    EXPECT_EQ(t, 0.1 * k);
    EXPECT_EQ(q.x, p.x);
  }
  // The live file itself can be opened read-only while the writer holds it.
  EXPECT_EQ(readSeries(path.string(), "kinetic_energy").size(), 4u);
}

// Run outputs keep each snapshot in a file of its own, linked from the main file: the readers
// see the same snapshots through the links, the main file holds no particle data, and a
// dropped snapshot's file goes with it.
TEST(Hdf5Writer, SnapshotFilesAreLinkedAndReadBack) {
  const fs::path dir = freshFolder("linked");
  const fs::path path = dir / "mpm.h5";
  const auto p = makeParticles(2000);
  {
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Truncate, true);
    for (int k = 0; k < 3; ++k) {
      w.appendScalar("time", 0.1 * k);
      EXPECT_EQ(w.writeSnapshot(p, 0.1 * k, 10 * k), k);
    }
  }
  EXPECT_EQ(snapshotFolder(path.string()), "mpm.snapshots");
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(fs::exists(dir / "mpm.snapshots" / ("00000" + std::to_string(k) + ".h5")));
  // 2000 particles x 19 values x 8 B = 304 kB per snapshot: none of it in the main file
  EXPECT_LT(fs::file_size(path), 100000u);
  EXPECT_EQ(readNumSnapshots(path.string()), 3);
  mpm::ParticleSet q;
  double t = 0;
  long step = 0;
  readSnapshot(path.string(), 2, q, &t, &step);
  EXPECT_EQ(t, 0.1 * 2);
  EXPECT_EQ(step, 20);
  EXPECT_EQ(q.x, p.x);
  EXPECT_EQ(q.stress, p.stress);
  EXPECT_EQ(q.phase, p.phase);
  {
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Append, true);
    EXPECT_EQ(w.dropSnapshotsAfter(0.15), 2);
  }
  EXPECT_EQ(readNumSnapshots(path.string()), 2);
  EXPECT_FALSE(fs::exists(dir / "mpm.snapshots" / "000002.h5"));
  EXPECT_TRUE(fs::exists(dir / "mpm.snapshots" / "000001.h5"));
  // A new run in the same place starts without the old snapshot files.
  { Hdf5Writer w(path.string(), Hdf5Writer::Mode::Truncate, true); }
  EXPECT_EQ(readNumSnapshots(path.string()), 0);
  EXPECT_TRUE(fs::is_empty(dir / "mpm.snapshots"));
}

// What a run killed while HDF5 rewrote its metadata leaves: a damaged main file. The restart
// puts back the copy of the last commit: records and snapshots up to that commit, exactly, and
// the run appends from there.
TEST(Hdf5Writer, ResumeFromCommitRestoresADamagedFile) {
  const fs::path dir = freshFolder("resume");
  const fs::path path = dir / "mpm.h5";
  const auto p = makeParticles(5);
  EXPECT_FALSE(resumeFromCommit(path.string()));  // nothing committed: nothing to restore
  {
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Truncate, true);
    for (int k = 0; k < 4; ++k) w.appendScalar("time", 0.1 * k);
    w.writeSnapshot(p, 0.3, 3);
    w.commit();
    for (int k = 4; k < 9; ++k) w.appendScalar("time", 0.1 * k);
    w.writeSnapshot(p, 0.8, 8);
  }
  EXPECT_EQ(readSeries(path.string(), "time").size(), 9u);
  {  // the damage: the first half of the file overwritten
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    const std::string junk(fs::file_size(path) / 2, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  EXPECT_THROW(readSeries(path.string(), "time"), RuntimeFailure);
  ASSERT_TRUE(resumeFromCommit(path.string()));
  const auto time = readSeries(path.string(), "time");
  ASSERT_EQ(time.size(), 4u);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(time[k], 0.1 * k);
  EXPECT_EQ(readNumSnapshots(path.string()), 1);
  {
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Append, true);
    EXPECT_EQ(w.dropSnapshotsAfter(0.3), 1);
    w.appendScalar("time", 0.4);
    EXPECT_EQ(w.writeSnapshot(p, 0.4, 4), 1);  // index 1 again: the killed run's file replaced
  }
  EXPECT_EQ(readSeries(path.string(), "time").size(), 5u);
  double t = 0;
  mpm::ParticleSet q;
  readSnapshot(path.string(), 1, q, &t);
  EXPECT_EQ(t, 0.4);
  EXPECT_EQ(q.v, p.v);
}

// A restart drops a snapshot (and its file) past its checkpoint and is killed before its next
// commit: the copy it goes back to still links that snapshot, whose file is gone. The next
// restart drops it again rather than failing on it.
TEST(Hdf5Writer, ADroppedSnapshotsLinkLeftInTheCopyIsDroppedAgain) {
  const fs::path dir = freshFolder("dangling");
  const fs::path path = dir / "mpm.h5";
  const auto p = makeParticles(3);
  {
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Truncate, true);
    for (int k = 0; k < 3; ++k) w.writeSnapshot(p, 0.1 * k, k);
    w.commit();
  }
  for (int attempt = 0; attempt < 2; ++attempt) {
    ASSERT_TRUE(resumeFromCommit(path.string()));
    Hdf5Writer w(path.string(), Hdf5Writer::Mode::Append, true);
    EXPECT_EQ(w.dropSnapshotsAfter(0.05), 1) << "restart " << attempt;
  }
  EXPECT_FALSE(fs::exists(dir / "mpm.snapshots" / "000001.h5"));
  EXPECT_TRUE(fs::exists(dir / "mpm.snapshots" / "000000.h5"));
}

TEST(Hdf5Writer, RejectsInconsistentRecords) {
  const fs::path path = scratch("bad.h5");
  Hdf5Writer w(path.string());
  w.appendVector("com", {1, 2, 3});
  try {
    w.appendVector("com", {1, 2});
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("series 'com'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("length 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(w.appendScalar("com", 1.0), ParameterError);
  EXPECT_THROW(w.appendScalar("a/b", 1.0), ParameterError);
  auto p = makeParticles(3);
  p.J.pop_back();
  try {
    w.writeSnapshot(p, 0, 0);
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("ParticleSet.J"), std::string::npos) << e.what();
  }
  // the file, what failed and the system's reason (a full disk reads "No space left on device":
  // scripts/checks/check_fault_injection.py --kinds driver-full)
  try {
    Hdf5Writer("/nonexistent-dir/x.h5");
    FAIL() << "expected RuntimeFailure";
  } catch (const RuntimeFailure& e) {
    EXPECT_EQ(std::string(e.what()),
              "HDF5 file '/nonexistent-dir/x.h5': cannot create (No such file or directory)");
  }
}

#endif  // MPMSDEM_WITH_HDF5

TEST(VtkWriter, AsciiParticlesParseBack) {
  const fs::path path = scratch("p.vtp");
  const auto p = makeParticles(5);
  writeParticlesVtp(path.string(), p, VtkEncoding::Ascii);
  const std::string text = slurp(path);
  EXPECT_EQ(intAttribute(text, "NumberOfPoints"), 5);
  EXPECT_EQ(intAttribute(text, "NumberOfVerts"), 1);
  const auto pts = asciiArray(text, "Points");
  ASSERT_EQ(pts.size(), 15u);
  EXPECT_NEAR(pts[3 * 4 + 2], p.x[3 * 4 + 2], 1e-7 * std::fabs(p.x[14]));
  const auto pressure = asciiArray(text, "pressure");
  ASSERT_EQ(pressure.size(), 5u);
  const double p2 = -(p.stress[12] + p.stress[13] + p.stress[14]) / 3;  // particle 2
  EXPECT_NEAR(pressure[2], p2, 1e-6 * std::fabs(p2));
  const auto stress = asciiArray(text, "stress");
  ASSERT_EQ(stress.size(), 45u);
  // Full tensor of particle 1: [xx xy xz; xy yy yz; xz yz zz] from (xx yy zz yz xz xy).
  const double* s = &p.stress[6];
  const double full[9] = {s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]};
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(stress[9 + k], full[k], 1e-6 * std::fabs(full[k]));
  const auto phase = asciiArray(text, "phase");
  ASSERT_EQ(phase.size(), 5u);
  EXPECT_EQ(phase[4], 1.0);
  const auto density = asciiArray(text, "density");
  EXPECT_NEAR(density[0], 1600.0, 1e-3);
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
}

TEST(VtkWriter, RawParticlesParseBack) {
  const fs::path path = scratch("p_raw.vtp");
  const auto p = makeParticles(6);
  writeParticlesVtp(path.string(), p, VtkEncoding::AppendedRaw);
  const std::string text = slurp(path);
  EXPECT_EQ(intAttribute(text, "NumberOfPoints"), 6);
  const auto v = rawFloatArray(text, "velocity");
  ASSERT_EQ(v.size(), 18u);
  for (int k = 0; k < 18; ++k) EXPECT_NEAR(v[k], p.v[k], 1e-6 * std::fabs(p.v[k]) + 1e-12);
  const auto gdp = rawFloatArray(text, "gammaDotP");
  ASSERT_EQ(gdp.size(), 6u);
  EXPECT_NEAR(gdp[5], 2.5 + 1.0 / 9.0, 1e-6);
  const auto pts = rawFloatArray(text, "Points");
  ASSERT_EQ(pts.size(), 18u);
  EXPECT_NEAR(pts[0], 1.0 / 3.0, 1e-7);
  // Raw is much smaller than ascii for the same data.
  const fs::path ascii = scratch("p_ascii.vtp");
  writeParticlesVtp(ascii.string(), makeParticles(2000), VtkEncoding::Ascii);
  writeParticlesVtp(path.string(), makeParticles(2000), VtkEncoding::AppendedRaw);
  EXPECT_LT(fs::file_size(path), fs::file_size(ascii) / 2);
}

// A set handed out in slices of `size` particles (copies), as a solver hands out its own.
class SetInSlices : public mpm::ParticleSlices {
 public:
  SetInSlices(const mpm::ParticleSet& set, std::size_t size) : set_(set), size_(size) {}
  std::size_t size() const override { return set_.size(); }
  std::size_t sliceSize() const override { return size_; }
  const mpm::ParticleSet& slice(std::size_t first, std::size_t count) override {
    ++calls;
    mpm::copyParticleRange(set_, first, count, buf_);
    return buf_;
  }
  int calls = 0;

 private:
  const mpm::ParticleSet& set_;
  std::size_t size_;
  mpm::ParticleSet buf_;
};

// Outputs written from slices (3 particles at a time, a short last one) are the files the whole
// set gives: the same bytes for VTK (raw and ascii), the same values for the HDF5 snapshot.
TEST(ParticleSlices, SlicedOutputsAreTheWholeSetsFiles) {
  for (const std::size_t n : {0, 1, 10}) {
    const auto p = makeParticles(n);
    for (const VtkEncoding enc : {VtkEncoding::AppendedRaw, VtkEncoding::Ascii}) {
      const fs::path whole = scratch("whole.vtp"), sliced = scratch("sliced.vtp");
      writeParticlesVtp(whole.string(), p, enc);
      SetInSlices slices(p, 3);
      writeParticlesVtp(sliced.string(), slices, enc);
      EXPECT_EQ(slices.calls, static_cast<int>((n + 2) / 3));
      EXPECT_EQ(slurp(sliced), slurp(whole)) << n << " particles";
    }
#ifdef MPMSDEM_WITH_HDF5
    const fs::path path = scratch("sliced.h5");
    {
      Hdf5Writer w(path.string());
      SetInSlices slices(p, 3);
      EXPECT_EQ(w.writeSnapshot(p, 0.25, 1), 0);
      EXPECT_EQ(w.writeSnapshot(slices, 0.25, 1), 1);
    }
    mpm::ParticleSet a, b;
    readSnapshot(path.string(), 0, a);
    readSnapshot(path.string(), 1, b);
    ASSERT_EQ(a.size(), n);
    EXPECT_EQ(a.x, b.x);
    EXPECT_EQ(a.v, b.v);
    EXPECT_EQ(a.stress, b.stress);
    EXPECT_EQ(a.mass, b.mass);
    EXPECT_EQ(a.volume0, b.volume0);
    EXPECT_EQ(a.J, b.J);
    EXPECT_EQ(a.gammaDotP, b.gammaDotP);
    EXPECT_EQ(a.phase, b.phase);
    EXPECT_EQ(a.x, p.x);
    EXPECT_EQ(a.J, p.J);
    // and read back 3 at a time (what --restart loads)
    SnapshotSlices back(path.string(), 1, 3);
    EXPECT_EQ(back.size(), n);
    EXPECT_EQ(back.time(), 0.25);
    EXPECT_EQ(back.step(), 1);
    for (std::size_t first = 0; first < n; first += 3) {
      const std::size_t count = std::min<std::size_t>(3, n - first);
      const mpm::ParticleSet& q = back.slice(first, count);
      for (std::size_t i = 0; i < count; ++i) {
        for (int d = 0; d < 3; ++d) EXPECT_EQ(q.x[3 * i + d], p.x[3 * (first + i) + d]);
        for (int k = 0; k < 6; ++k) EXPECT_EQ(q.stress[6 * i + k], p.stress[6 * (first + i) + k]);
        EXPECT_EQ(q.mass[i], p.mass[first + i]);
        EXPECT_EQ(q.phase[i], p.phase[first + i]);
        EXPECT_EQ(q.fext[3 * i], 0.0);
      }
    }
    EXPECT_THROW(back.slice(n, 1), ParameterError);
#endif
  }
}

TEST(VtkWriter, RigidSurfacesWithBodyIds) {
  const fs::path path = scratch("bodies.vtp");
  RigidSurface a, b;
  a.id = 3;
  a.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  a.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  b = a;
  b.id = 7;
  for (auto& v : b.vertices) v[0] += 2.0;
  writeRigidSurfacesVtp(path.string(), {a, b}, VtkEncoding::Ascii);
  const std::string text = slurp(path);
  EXPECT_EQ(intAttribute(text, "NumberOfPoints"), 8);
  EXPECT_EQ(intAttribute(text, "NumberOfPolys"), 8);
  const auto ids = asciiArray(text, "bodyId");
  ASSERT_EQ(ids.size(), 8u);
  EXPECT_EQ(ids[0], 3.0);
  EXPECT_EQ(ids[7], 7.0);
  const auto conn = asciiArray(text, "connectivity");
  ASSERT_EQ(conn.size(), 24u);
  EXPECT_EQ(conn[12], 4.0);  // body b, triangle 0, vertex 0 -> 4 + 0
  EXPECT_EQ(conn[23], 7.0);  // body b, triangle 3, vertex 3 -> 4 + 3
  const auto offs = asciiArray(text, "offsets");
  ASSERT_EQ(offs.size(), 8u);
  EXPECT_EQ(offs[7], 24.0);
  const auto pts = asciiArray(text, "Points");
  EXPECT_EQ(pts[3 * 5 + 0], 3.0);  // vertex 1 of body b: (1 + 2, 0, 0)

  b.triangles[2][1] = 4;
  try {
    writeRigidSurfacesVtp(path.string(), {a, b});
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("body 7 triangle 2"), std::string::npos) << e.what();
  }
}

TEST(VtkWriter, ContactsWithForcesAndFeatures) {
  const fs::path path = scratch("contacts.vtp");
  ContactPoint a, b;
  a.point = {0.1, 0.2, 0.3};
  a.force = {1.5, 0, -0.25};
  a.normalForce = 1.5;
  a.blockId = 4;
  a.particle = 17;
  b = a;
  b.point[0] = 0.4;
  b.particle = 99;
  b.feature = 1;
  writeContactsVtp(path.string(), {a, b}, VtkEncoding::Ascii);
  const std::string text = slurp(path);
  EXPECT_EQ(intAttribute(text, "NumberOfPoints"), 2);
  EXPECT_EQ(intAttribute(text, "NumberOfVerts"), 2);  // one cell a contact: each is drawn and picked alone
  const auto f = asciiArray(text, "force");
  ASSERT_EQ(f.size(), 6u);
  EXPECT_NEAR(f[5], -0.25, 1e-7);
  EXPECT_EQ(asciiArray(text, "particle")[1], 99.0);
  EXPECT_EQ(asciiArray(text, "feature")[1], 1.0);
  EXPECT_EQ(asciiArray(text, "blockId")[0], 4.0);
  EXPECT_NEAR(asciiArray(text, "Points")[3], 0.4, 1e-7);
  EXPECT_EQ(asciiArray(text, "offsets")[1], 2.0);
  writeContactsVtp(path.string(), {});  // a step without contacts: an empty, valid file
  EXPECT_EQ(intAttribute(slurp(path), "NumberOfPoints"), 0);
  b.feature = 3;
  try {
    writeContactsVtp(path.string(), {a, b});
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("contact 1 feature"), std::string::npos) << e.what();
  }
}

TEST(PvdCollection, RewrittenAfterEachAddAndResumable) {
  const fs::path path = scratch("series.pvd");
  {
    PvdCollection c(path.string());
    c.add(0.0, "vtk/p_000000.vtp");
    c.add(0.05, "vtk/p_000001.vtp");
    c.add(0.1, "vtk/bodies_000002.vtp", 1);
    const std::string text = slurp(path);  // valid while the run goes on
    EXPECT_NE(text.find("</VTKFile>"), std::string::npos);
    const std::regex dataset("<DataSet ");
    EXPECT_EQ(std::distance(std::sregex_iterator(text.begin(), text.end(), dataset), std::sregex_iterator()), 3);
  }
  PvdCollection resumed(path.string(), true);
  EXPECT_EQ(resumed.size(), 3u);
  EXPECT_EQ(resumed.count(0), 2u);
  EXPECT_EQ(resumed.count(1), 1u);
  resumed.add(0.15, "vtk/p&q.vtp");
  const std::string text = slurp(path);
  EXPECT_NE(text.find("timestep=\"0.10000000000000001\" group=\"\" part=\"1\" file=\"vtk/bodies_000002.vtp\""),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("file=\"vtk/p&amp;q.vtp\""), std::string::npos) << text;
  PvdCollection again(path.string(), true);
  EXPECT_EQ(again.size(), 4u);
  again.add(0.2, "x.vtp");
  EXPECT_NE(slurp(path).find("file=\"vtk/p&amp;q.vtp\""), std::string::npos);
  PvdCollection fresh(path.string(), false);
  EXPECT_EQ(fresh.size(), 0u);
}
