#include "coupling/CoupledCheckpoint.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "common/Error.hpp"
#include "mpm/MpmTypes.hpp"

namespace mpmsdem {
namespace coupling {

namespace {

using nlohmann::json;
constexpr const char* kFormat = "mpmsdem-driver-coupled-1";
constexpr const char* kFrontFormat = "mpmsdem-front-snapshot-1";

json vec(const Vec3& v) { return json::array({v[0], v[1], v[2]}); }
json quat(const Quat& q) { return json::array({q.w(), q.x(), q.y(), q.z()}); }
// JSON has no infinity: a step without a limit is null.
json step(double s) { return std::isfinite(s) ? json(s) : json(); }

// The fields of a record as they are read: a value of another JSON type, or a number beyond the
// range of the C++ field it goes to (whose conversion would be undefined), is a ParameterError
// naming the field; the callers add the file.
std::string shown(const json& v) { return v.is_number() ? v.dump() : std::string("a JSON ") + v.type_name(); }

const json& member(const json& obj, const std::string& path, const char* key) {
  if (!obj.is_object()) throwParameter(path.empty() ? "the record" : path, shown(obj), "", "a JSON object");
  if (!obj.contains(key)) throw ParameterError("missing key '" + (path.empty() ? key : path + "." + key) + "'");
  return obj.at(key);
}

const json& list(const json& v, const std::string& name, std::size_t size = 0) {
  if (!v.is_array() || (size && v.size() != size))
    throwParameter(name, v.is_array() ? std::to_string(v.size()) + " values" : shown(v), "",
                   size ? "an array of " + std::to_string(size) + " values" : std::string("an array"));
  return v;
}

double real(const json& v, const std::string& name) {
  if (!v.is_number()) throwParameter(name, shown(v), "", "a number");
  return v.get<double>();
}

long long integer(const json& v, const std::string& name, long long lo, long long hi) {
  bool ok = v.is_number_integer();
  long long x = 0;
  if (v.is_number_unsigned())
    ok = v.get<unsigned long long>() <= static_cast<unsigned long long>(std::numeric_limits<long long>::max());
  if (ok) x = v.get<long long>();
  if (!ok || x < lo || x > hi)
    throwParameter(name, shown(v), "", "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return x;
}

constexpr long long kIntMax = std::numeric_limits<int>::max(), kIntMin = std::numeric_limits<int>::min();
constexpr long long kLongMax = std::numeric_limits<long>::max();

Vec3 toVec(const json& j, const std::string& name) {
  list(j, name, 3);
  return Vec3(real(j[0], name + "[0]"), real(j[1], name + "[1]"), real(j[2], name + "[2]"));
}
Quat toQuat(const json& j, const std::string& name) {
  list(j, name, 4);
  return Quat(real(j[0], name + "[0]"), real(j[1], name + "[1]"), real(j[2], name + "[2]"), real(j[3], name + "[3]"));
}
double toStep(const json& j, double none, const std::string& name) { return j.is_null() ? none : real(j, name); }

// Through a temporary file renamed over `path`: a run killed while writing leaves the old file.
void writeAtomically(const std::string& path, const json& j, const char* what) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    f << j.dump();
    f.flush();
    if (!f) throw RuntimeFailure(std::string(what) + ": cannot write " + tmp);
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw RuntimeFailure(std::string(what) + ": cannot rename " + tmp + " to " + path + ": " + ec.message());
}


// The SDEM side of a checkpoint: the blocks' states, clock, contact histories and dissipations.
void captureBlocks(CoupledWorld& w, CoupledCheckpoint& c) {
  const sdem::SdemEngine& e = w.world.engine;
  c.pos.clear();
  c.ori.clear();
  c.vel.clear();
  c.angVel.clear();
  c.hasAngMom.clear();
  c.angMom.clear();
  for (int i = 0; i < e.numBodies(); ++i) {
    c.pos.push_back(e.position(i));
    c.ori.push_back(e.orientation(i));
    c.vel.push_back(e.velocity(i));
    c.angVel.push_back(e.angularVelocity(i));
    Vec3 L = Vec3::Zero();
    c.hasAngMom.push_back(w.world.angularMomentum(i, L) ? 1 : 0);
    c.angMom.push_back(L);
  }
  c.worldTime = w.world.time();
  c.sdemHistories = e.contactHistories();
  c.sdemFriction = e.frictionDissipation();
  c.sdemDamping = e.dampingDissipation();
}
}  // namespace

CoupledCheckpoint captureCheckpoint(CoupledWorld& w, long snapshot, double lastDt,
                                    const std::vector<Quat>& referenceOrientations) {
  CoupledCheckpoint c;
  c.snapshot = snapshot;
  c.step = w.mpm().steps();
  c.time = w.mpm().time();
  c.lastDt = lastDt;
  c.contactStep = w.contactStep();
  c.contactStepLow = w.contactStepLow();
  c.particleApproachStep = w.coupling.particleApproachStep();
  captureBlocks(w, c);
  c.historySlots = w.coupling.historySlots();
  w.coupling.pullHistories();
  const std::vector<long long>& keys = w.coupling.historyKeys();
  c.historyParticles = static_cast<long>(keys.size() / std::max(c.historySlots, 1));
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (keys[k] < 0) continue;  // an empty slot
    c.historyIndex.push_back(static_cast<long long>(k));
    c.historyKey.push_back(keys[k]);
    for (int d = 0; d < 3; ++d) c.historyXi.push_back(w.coupling.historyXiAt(k, d));
  }
  c.couplingFriction = w.coupling.frictionDissipation();
  c.couplingDamping = w.coupling.dampingDissipation();
  // (a block no coupling step has reached yet has taken no impulse)
  c.couplingImpulse = w.coupling.impulses();
  c.couplingImpulse.resize(CouplingReport::kImpulseValues * c.pos.size(), 0.0);
  c.couplingFirstContact = w.coupling.firstContacts();
  c.couplingFirstContact.resize(c.pos.size(), std::numeric_limits<double>::quiet_NaN());
  c.referenceOrientations = referenceOrientations;
  return c;
}

void writeCheckpoint(const std::string& path, const CoupledCheckpoint& c) {
  json j;
  j["format"] = kFormat;
  j["snapshot"] = c.snapshot;
  j["step"] = c.step;
  j["time"] = c.time;
  j["world_time"] = c.worldTime;
  j["last_dt"] = c.lastDt;
  j["contact_step"] = step(c.contactStep);
  j["contact_step_low"] = json::array({step(c.contactStepLow.step), step(c.contactStepLow.time)});
  j["particle_approach_step"] = step(c.particleApproachStep);
  json bodies = json::array();
  for (std::size_t i = 0; i < c.pos.size(); ++i)
    bodies.push_back({{"pos", vec(c.pos[i])},
                      {"ori", quat(c.ori[i])},
                      {"vel", vec(c.vel[i])},
                      {"ang_vel", vec(c.angVel[i])},
                      {"ang_mom", c.hasAngMom[i] ? vec(c.angMom[i]) : json()}});
  j["bodies"] = bodies;
  json sh = json::array();
  for (const auto& h : c.sdemHistories)
    sh.push_back({h.key.bodyA, h.key.bodyB, static_cast<int>(h.key.kindA), static_cast<int>(h.key.kindB), h.key.indexA,
                  h.key.indexB, h.xi[0], h.xi[1], h.xi[2]});
  j["sdem_histories"] = sh;
  j["sdem_dissipation"] = {c.sdemFriction, c.sdemDamping};
  j["history_slots"] = c.historySlots;
  j["history_particles"] = c.historyParticles;
  json ch = json::array();
  for (std::size_t k = 0; k < c.historyIndex.size(); ++k)
    ch.push_back({c.historyIndex[k], c.historyKey[k], c.historyXi[3 * k], c.historyXi[3 * k + 1], c.historyXi[3 * k + 2]});
  j["coupling_histories"] = ch;
  j["coupling_dissipation"] = {c.couplingFriction, c.couplingDamping};
  json ci = json::array();
  const std::size_t nv = CouplingReport::kImpulseValues;
  for (std::size_t i = 0; i + nv <= c.couplingImpulse.size(); i += nv)
    ci.push_back(std::vector<double>(c.couplingImpulse.begin() + i, c.couplingImpulse.begin() + i + nv));
  j["coupling_impulse"] = ci;
  // (a time not kept, -inf, is written null too: the impulse tells it from "not yet" at the restart)
  json fc = json::array();
  for (double t : c.couplingFirstContact) fc.push_back(step(t));
  j["coupling_first_contact"] = fc;
  json ro = json::array();
  for (const Quat& q : c.referenceOrientations) ro.push_back(quat(q));
  j["reference_orientations"] = ro;

  writeAtomically(path, j, "coupled checkpoint");
}

CoupledCheckpoint readCheckpoint(const std::string& path, const std::string& option) {
  std::ifstream f(path);
  if (!f)
    throw ParameterError(option + ": " + path +
                         " is missing; a coupled run goes on from the checkpoint its outputs hold, which "
                         "mpmsdem-run writes beside every snapshot");
  CoupledCheckpoint c;
  try {
    const json j = json::parse(f);
    if (!j.is_object() || j.value("format", "") != kFormat)
      throw ParameterError("format: not \"" + std::string(kFormat) + "\"");
    c.snapshot = integer(member(j, "", "snapshot"), "snapshot", 0, kLongMax);
    c.step = integer(member(j, "", "step"), "step", 0, kLongMax);
    c.time = real(member(j, "", "time"), "time");
    c.worldTime = real(member(j, "", "world_time"), "world_time");
    c.lastDt = real(member(j, "", "last_dt"), "last_dt");
    const double inf = std::numeric_limits<double>::infinity();
    c.contactStep = toStep(member(j, "", "contact_step"), inf, "contact_step");
    const json& low = list(member(j, "", "contact_step_low"), "contact_step_low", 2);
    c.contactStepLow.step = toStep(low[0], inf, "contact_step_low[0]");
    c.contactStepLow.time = toStep(low[1], std::nan(""), "contact_step_low[1]");
    c.particleApproachStep = toStep(member(j, "", "particle_approach_step"), inf, "particle_approach_step");
    const json& bodies = list(member(j, "", "bodies"), "bodies");
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const json& b = bodies[i];
      const std::string at = "bodies[" + std::to_string(i) + "]";
      c.pos.push_back(toVec(member(b, at, "pos"), at + ".pos"));
      c.ori.push_back(toQuat(member(b, at, "ori"), at + ".ori"));
      c.vel.push_back(toVec(member(b, at, "vel"), at + ".vel"));
      c.angVel.push_back(toVec(member(b, at, "ang_vel"), at + ".ang_vel"));
      const json& L = member(b, at, "ang_mom");
      c.hasAngMom.push_back(L.is_null() ? 0 : 1);
      c.angMom.push_back(L.is_null() ? Vec3::Zero() : toVec(L, at + ".ang_mom"));
    }
    const json& sh = list(member(j, "", "sdem_histories"), "sdem_histories");
    for (std::size_t k = 0; k < sh.size(); ++k) {
      const std::string at = "sdem_histories[" + std::to_string(k) + "]";
      const json& h = list(sh[k], at, 9);
      auto field = [&](int i) { return at + "[" + std::to_string(i) + "]"; };
      sdem::ContactHistoryEntry e;
      e.key.bodyA = static_cast<int>(integer(h[0], field(0), kIntMin, kIntMax));
      e.key.bodyB = static_cast<int>(integer(h[1], field(1), kIntMin, kIntMax));
      e.key.kindA = static_cast<sdem::FeatureKind>(integer(h[2], field(2), 0, 2));  // face, edge, vertex
      e.key.kindB = static_cast<sdem::FeatureKind>(integer(h[3], field(3), 0, 2));
      e.key.indexA = static_cast<int>(integer(h[4], field(4), kIntMin, kIntMax));
      e.key.indexB = static_cast<int>(integer(h[5], field(5), kIntMin, kIntMax));
      e.xi = Vec3(real(h[6], field(6)), real(h[7], field(7)), real(h[8], field(8)));
      c.sdemHistories.push_back(e);
    }
    const json& sd = list(member(j, "", "sdem_dissipation"), "sdem_dissipation", 2);
    c.sdemFriction = real(sd[0], "sdem_dissipation[0]");
    c.sdemDamping = real(sd[1], "sdem_dissipation[1]");
    c.historySlots = static_cast<int>(integer(member(j, "", "history_slots"), "history_slots", 0, kIntMax));
    c.historyParticles = integer(member(j, "", "history_particles"), "history_particles", 0, kLongMax);
    const json& ch = list(member(j, "", "coupling_histories"), "coupling_histories");
    for (std::size_t k = 0; k < ch.size(); ++k) {
      const std::string at = "coupling_histories[" + std::to_string(k) + "]";
      const json& h = list(ch[k], at, 5);
      c.historyIndex.push_back(integer(h[0], at + "[0]", 0, std::numeric_limits<long long>::max()));
      c.historyKey.push_back(integer(h[1], at + "[1]", 0, std::numeric_limits<long long>::max()));
      for (int d = 0; d < 3; ++d) c.historyXi.push_back(real(h[2 + d], at + "[" + std::to_string(2 + d) + "]"));
    }
    const json& cd = list(member(j, "", "coupling_dissipation"), "coupling_dissipation", 2);
    c.couplingFriction = real(cd[0], "coupling_dissipation[0]");
    c.couplingDamping = real(cd[1], "coupling_dissipation[1]");
    // (absent from checkpoints written before it was kept: the impulse then counts from the restart)
    if (j.contains("coupling_impulse")) {
      const json& ci = list(j["coupling_impulse"], "coupling_impulse");
      if (ci.size() != bodies.size())
        throwParameter("coupling_impulse", std::to_string(ci.size()) + " entries", "",
                       "one per block of \"bodies\" (" + std::to_string(bodies.size()) + " blocks)");
      for (std::size_t i = 0; i < ci.size(); ++i) {
        const std::string at = "coupling_impulse[" + std::to_string(i) + "]";
        const json& v = list(ci[i], at, CouplingReport::kImpulseValues);
        for (int k = 0; k < CouplingReport::kImpulseValues; ++k)
          c.couplingImpulse.push_back(real(v[k], at + "[" + std::to_string(k) + "]"));
      }
    }
    if (j.contains("coupling_first_contact")) {
      const json& fc = list(j["coupling_first_contact"], "coupling_first_contact", bodies.size());
      for (std::size_t i = 0; i < fc.size(); ++i) {
        const std::string at = "coupling_first_contact[" + std::to_string(i) + "]";
        const double t = toStep(fc[i], std::numeric_limits<double>::quiet_NaN(), at);
        if (!(std::isnan(t) || (std::isfinite(t) && t >= 0))) throwParameter(at, t, "s", ">= 0 or null");
        c.couplingFirstContact.push_back(t);
      }
    }
    const json& ro = list(member(j, "", "reference_orientations"), "reference_orientations");
    for (std::size_t k = 0; k < ro.size(); ++k)
      c.referenceOrientations.push_back(toQuat(ro[k], "reference_orientations[" + std::to_string(k) + "]"));
  } catch (const json::exception& e) {
    throw ParameterError(option + ": " + path + " is not a readable coupled checkpoint: " + e.what());
  } catch (const ParameterError& e) {
    throw ParameterError(option + ": " + path + ": " + e.what());
  }
  return c;
}

void restoreCheckpoint(const CoupledCheckpoint& c, CoupledWorld& w) {
  sdem::SdemEngine& e = w.world.engine;
  const int n = e.numBodies();
  if (static_cast<int>(c.pos.size()) != n)
    throwParameter("--restart: checkpoint blocks", c.pos.size(), "", "the scene's " + std::to_string(n) + " blocks");
  const long np = static_cast<long>(w.mpm().numParticles());
  if (c.historyParticles != 0 && c.historyParticles != np)
    throwParameter("--restart: checkpoint MP-block histories", c.historyParticles, "particles",
                   "the snapshot's " + std::to_string(np) + " particles");
  for (int i = 0; i < n; ++i) {
    e.setState(i, c.pos[i], c.ori[i], c.vel[i], c.angVel[i]);
    if (c.hasAngMom[i]) w.world.restoreAngularMomentum(i, c.angMom[i]);
  }
  w.world.setTime(c.worldTime);
  e.setContactHistories(c.sdemHistories);
  e.setDissipation(c.sdemFriction, c.sdemDamping);
  w.coupling.setHistorySlots(c.historySlots);
  if (c.historyParticles > 0) {
    const std::size_t size = static_cast<std::size_t>(c.historySlots) * static_cast<std::size_t>(np);
    std::vector<long long> keys(size, -1);
    std::vector<double> xi(3 * size, 0.0);
    for (std::size_t k = 0; k < c.historyIndex.size(); ++k) {
      const long long at = c.historyIndex[k];
      if (at < 0 || static_cast<std::size_t>(at) >= size)
        throwParameter("--restart: checkpoint history slot", at, "", "in [0, " + std::to_string(size) + ")");
      keys[at] = c.historyKey[k];
      for (int d = 0; d < 3; ++d) xi[3 * at + d] = c.historyXi[3 * k + d];
    }
    w.coupling.setHistories(keys, xi);
  }
  w.coupling.setDissipation(c.couplingFriction, c.couplingDamping);
  if (!c.couplingImpulse.empty() && c.couplingImpulse.size() != static_cast<std::size_t>(CouplingReport::kImpulseValues) * n)
    throwParameter("--restart: checkpoint coupling_impulse", c.couplingImpulse.size() / CouplingReport::kImpulseValues,
                   "blocks", "the scene's " + std::to_string(n) + " blocks");
  w.coupling.setImpulses(c.couplingImpulse);
  if (!c.couplingFirstContact.empty() && c.couplingFirstContact.size() != static_cast<std::size_t>(n))
    throwParameter("--restart: checkpoint coupling_first_contact", c.couplingFirstContact.size(), "blocks",
                   "the scene's " + std::to_string(n) + " blocks");
  w.coupling.restoreFirstContacts(c.couplingFirstContact, !c.couplingImpulse.empty(), n);
  w.coupling.restoreParticleApproachStep(c.particleApproachStep);
  w.restoreContactSteps(c.contactStep, c.contactStepLow);
}

void writeFrontSnapshot(const std::string& path, const FrontSnapshot& f) {
  json j = {{"format", kFrontFormat}, {"x", f.x},       {"front_x", f.frontX}, {"snapshot", f.snapshot},
            {"time", f.time},        {"step", f.step}, {"checkpoint", f.checkpoint.empty() ? json() : json(f.checkpoint)}};
  writeAtomically(path, j, "front snapshot");
}

FrontSnapshot readFrontSnapshot(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw ParameterError("--flow-from: " + path + " is missing: the run in that folder wrote no state to start from "
                         "(give its scene run.snapshot_when_front_at, upstream of this scene's blocks, and run it again)");
  FrontSnapshot f;
  try {
    const json j = json::parse(in);
    if (!j.is_object() || j.value("format", "") != kFrontFormat)
      throw ParameterError("format: not \"" + std::string(kFrontFormat) + "\"");
    f.x = real(member(j, "", "x"), "x");
    f.frontX = real(member(j, "", "front_x"), "front_x");
    f.snapshot = integer(member(j, "", "snapshot"), "snapshot", 0, kLongMax);
    f.time = real(member(j, "", "time"), "time");
    f.step = integer(member(j, "", "step"), "step", 0, kLongMax);
    const json& ck = member(j, "", "checkpoint");
    if (!ck.is_null() && (!ck.is_string() || ck.get<std::string>().empty()))
      throwParameter("checkpoint", shown(ck), "", "null or the name of a checkpoint file beside the record");
    if (!ck.is_null()) f.checkpoint = ck.get<std::string>();
  } catch (const json::exception& e) {
    throw ParameterError("--flow-from: " + path + " is not a readable front snapshot record: " + e.what());
  } catch (const ParameterError& e) {
    throw ParameterError("--flow-from: " + path + ": " + e.what());
  }
  return f;
}

void startFromFlow(CoupledWorld& w, mpm::ParticleSlices& particles, long step, double time, double dt,
                   const CoupledCheckpoint* source, double reach) {
  sdem::SdemEngine& e = w.world.engine;
  const int n = e.numBodies();
  const int kept = source ? static_cast<int>(source->pos.size()) : 0;
  if (kept > n)
    throwParameter("--flow-from: the blocks of the run started from", kept, "", "at most this scene's " + std::to_string(n));
  for (int i = 0; i < kept; ++i)
    if (!e.isFixed(i) || e.position(i) != source->pos[i] || e.orientation(i).coeffs() != source->ori[i].coeffs())
      throw ParameterError("--flow-from: block " + std::to_string(e.externalId(i)) +
                           " of the run started from must be fixed, and this scene's block " + std::to_string(i) +
                           " must be it, fixed where it was: a block that moves would move without the flow's "
                           "forces in the steps this run does not take again");
  if (w.mpm().numParticles() != 0) throw ParameterError("--flow-from: the solver must start without particles");
  if (step < 0) throwParameter("--flow-from: step", step, "", ">= 0");
  if (!(dt > 0)) throwParameter("--flow-from: run.dt", dt, "s", "> 0 (a fixed step)");
  // What each new block does before the flow reaches it, in the steps the scene's own run takes:
  // without particles a coupled step moves the blocks alone (no MP contacts, no force buffer).
  for (long k = 0; k < step; ++k) w.step(dt);
  if (w.time() != time || w.mpm().time() != time) {
    char msg[256];
    std::snprintf(msg, sizeof msg, "%ld steps of run.dt = %.17g s reach t = %.17g s, the state started from is at "
                  "t = %.17g s: that run took other steps (both scenes need the same fixed run.dt)",
                  step, dt, w.time(), time);
    throw ParameterError("--flow-from: " + std::string(msg));
  }
  // No point may lie in a new block's bounding sphere grown by `reach`. The spheres sorted by
  // their lowest x: a point tests only those whose x extent holds it (a field's hundreds of
  // blocks against millions of points).
  std::vector<std::pair<double, int>> byLowX;
  double widest = 0;
  for (int i = kept; i < n; ++i) {
    const double r = e.shape(i).boundingRadius + reach;
    byLowX.push_back({e.position(i).x() - r, i});
    widest = std::max(widest, 2 * r);
  }
  std::sort(byLowX.begin(), byLowX.end());
  mpm::forEachSlice(particles, [&](std::size_t first, const mpm::ParticleSet& p) {
    for (std::size_t q = 0; q < p.size() && !byLowX.empty(); ++q) {
      const Vec3 x(p.x[3 * q], p.x[3 * q + 1], p.x[3 * q + 2]);
      auto b = std::lower_bound(byLowX.begin(), byLowX.end(), std::make_pair(x.x() - widest, -1));
      for (; b != byLowX.end() && b->first <= x.x(); ++b) {
        const int i = b->second;
        const double d = (x - e.position(i)).norm();
        if (d >= e.shape(i).boundingRadius + reach) continue;
        char msg[320];
        std::snprintf(msg, sizeof msg, "particle %zu is %.4g m from the centre of block %d at t = %.6g s, within "
                      "its bounding radius %.4g m and %.4g m: the flow had reached it there; start from a state "
                      "saved earlier (a smaller run.snapshot_when_front_at)",
                      first + q, d, e.externalId(i), time, e.shape(i).boundingRadius, reach);
        throw ParameterError("--flow-from: " + std::string(msg));
      }
    }
  });
  w.mpm().setParticles(particles);
  w.mpm().setClock(time, step);
  if (source) {
    // The new blocks' contact steps (with the fixed ones) and the source's MP contacts: the
    // scene's run had both, step by step; its lowest is the lower of the two.
    const double blocksStep = w.contactStep();
    const CoupledWorld::ContactStepLow blocksLow = w.contactStepLow();
    CoupledCheckpoint c = *source;
    captureBlocks(w, c);
    c.couplingImpulse.resize(CouplingReport::kImpulseValues * c.pos.size(), 0.0);  // no flow reached the new ones
    if (!c.couplingFirstContact.empty())
      c.couplingFirstContact.resize(c.pos.size(), std::numeric_limits<double>::quiet_NaN());
    c.contactStep = std::min(c.contactStep, blocksStep);
    if (blocksLow.step < c.contactStepLow.step) c.contactStepLow = blocksLow;
    restoreCheckpoint(c, w);
  }
}

}  // namespace coupling
}  // namespace mpmsdem
