// The run layer's step control and schedules: the time step a run takes (fixed, automatic, its
// floor, never past run.duration), when a run is over, when series, snapshots and progress lines
// are due, and how SIGINT and SIGTERM are caught.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/Error.hpp"
#include "scene/MpmScene.hpp"
#include "mpm/MpmSolver.hpp"
#include "run/OutputCadence.hpp"
#include "run/Progress.hpp"
#include "run/RunLoop.hpp"
#include "run/StopSignal.hpp"
#include "SandBox.hpp"

using namespace mpmsdem;
using namespace mpmsdem::run;

namespace {

struct SmallRun {
  explicit SmallRun(const std::string& runJson)
      : scene(testing_scenes::sandInABox(runJson)), solver(mpm::makeSolver(scene.params)), stepper(*solver) {
    mpm::SeededParticles seeded = mpm::seedParticleSlices(scene);
    solver->setParticles(seeded);
  }
  mpm::MpmScene scene;
  std::unique_ptr<mpm::MpmSolver> solver;
  Stepper stepper;
};

// The message of the RuntimeFailure that f throws ("" when it throws none).
template <class F>
std::string failureOf(F f) {
  try {
    f();
  } catch (const RuntimeFailure& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RunLoop, AutomaticStepIsTheFactorTimesTheCflStep) {
  SmallRun r(R"({"duration": 0.01, "dt": "auto", "dt_factor": 0.5, "output_every": 0.005})");
  const double cfl = r.solver->stableTimeStep();
  EXPECT_EQ(nextStep(r.stepper, r.scene.run, false), 0.5 * cfl);
  EXPECT_TRUE(r.stepper.automatic);
  EXPECT_EQ(r.stepper.limit(), "the flow's CFL step");
}

TEST(RunLoop, StepNeverPassesTheDuration) {
  SmallRun r(R"({"duration": 5e-4, "dt": 5e-5, "output_every": 1e-4})");
  EXPECT_EQ(r.stepper.limit(), "the fixed run.dt");
  EXPECT_EQ(nextStep(r.stepper, r.scene.run, true), 5e-5);
  r.solver->setClock(5e-4 - 2e-5, 9);
  EXPECT_EQ(nextStep(r.stepper, r.scene.run, true), 5e-4 - r.solver->time());
  EXPECT_LT(nextStep(r.stepper, r.scene.run, true), 5e-5);
  EXPECT_EQ(nextStep(r.stepper, r.scene.run, false), 5e-5);  // by steps: the whole step
}

TEST(RunLoop, FixedStepAboveTheStableOneIsAFailure) {
  SmallRun r(R"({"duration": 5e-4, "dt": 5e-5, "output_every": 1e-4})");
  mpm::RunSettings run = r.scene.run;
  run.dt = 2 * r.solver->stableTimeStep();
  const std::string m = failureOf([&] { nextStep(r.stepper, run, true); });
  EXPECT_NE(m.find("exceeds the stable step"), std::string::npos) << m;
  EXPECT_NE(m.find("the flow's CFL step"), std::string::npos) << m;
  run.dt = r.solver->stableTimeStep() * (1 + 0.5 * (kStepSlack - 1));  // within the slack: taken
  EXPECT_EQ(nextStep(r.stepper, run, false), run.dt);
}

TEST(RunLoop, AutomaticStepBelowTheFloorIsAFailure) {
  SmallRun r(R"({"duration": 0.01, "dt": "auto", "dt_factor": 0.5, "min_step_fraction": 0.6,
                 "output_every": 0.005})");
  const std::string m = failureOf([&] { nextStep(r.stepper, r.scene.run, true); });
  EXPECT_NE(m.find("below run.min_step_fraction = 0.6 of the flow's CFL step"), std::string::npos) << m;
  EXPECT_NE(m.find("It is set by the flow's CFL step"), std::string::npos) << m;
}

TEST(RunLoop, FinishedAndProgressByTimeAndBySteps) {
  SmallRun r(R"({"duration": 5e-4, "dt": 5e-5, "output_every": 1e-4})");
  const mpm::RunSettings& run = r.scene.run;
  EXPECT_FALSE(finished(*r.solver, run, 0));
  r.stepper.step(nextStep(r.stepper, run, true));
  EXPECT_DOUBLE_EQ(progressFraction(*r.solver, run, 0), 0.1);
  EXPECT_DOUBLE_EQ(progressFraction(*r.solver, run, 5), 0.2);
  EXPECT_DOUBLE_EQ(progressFraction(*r.solver, run, 5, 1), 0.0);  // a restart at step 1 to step 5
  EXPECT_TRUE(finished(*r.solver, run, 1));
  r.solver->setClock(5e-4 * (1 - 1e-13), 10);  // round-off short of the duration: over
  EXPECT_TRUE(finished(*r.solver, run, 0));
  EXPECT_FALSE(finished(*r.solver, run, 11));
}

TEST(OutputCadence, EachMultipleOnceAfterTheStart) {
  OutputCadence c(0.1, 0);
  EXPECT_EQ(c.next(), 0.1);
  // steps of 0.03 s to 1 s: one record at the first step at or past each multiple
  int records = 0;
  double last = 0;
  for (int k = 1; k <= 34; ++k) {  // to 1.02 s
    const double t = k * 0.03;
    if (c.due(t)) {
      ++records;
      EXPECT_GE(t - last, 0.09 - 1e-12);
      last = t;
      c.passed(t);
    }
  }
  EXPECT_EQ(records, 10);
  EXPECT_TRUE(OutputCadence(0.1, 0).due(0.1 * (1 - 1e-13)));  // round-off short of a multiple: due
  EXPECT_FALSE(OutputCadence(0.1, 0).due(0.1 * (1 - 1e-11)));
}

TEST(OutputCadence, ARestartAtAMultipleGoesOnToTheNext) {
  EXPECT_DOUBLE_EQ(OutputCadence(0.1, 0.3).next(), 0.4);
  EXPECT_DOUBLE_EQ(OutputCadence(0.1, 0.1 + 0.2).next(), 0.4);  // 0.30000000000000004
  EXPECT_DOUBLE_EQ(OutputCadence(0.1, 0.35).next(), 0.4);
  OutputCadence c(0.1, 0);
  c.passed(0.35);  // a step over several multiples: the next after it
  EXPECT_DOUBLE_EQ(c.next(), 0.4);
}

TEST(Progress, FivePercentMarksAndWallTime) {
  EXPECT_DOUBLE_EQ(ProgressSchedule::markAfter(0), 0.05);
  EXPECT_DOUBLE_EQ(ProgressSchedule::markAfter(0.05), 0.1);
  EXPECT_DOUBLE_EQ(ProgressSchedule::markAfter(0.42), 0.45);
  ProgressSchedule p(0.05, 3600);
  EXPECT_FALSE(p.due(0.04));
  EXPECT_TRUE(p.due(0.04, true));
  EXPECT_TRUE(p.due(0.05));
  p.reported(0.07);
  EXPECT_FALSE(p.due(0.09));
  EXPECT_TRUE(p.due(0.1));
  ProgressSchedule now(0.05, 0);  // a line due at every step by wall time
  EXPECT_TRUE(now.due(0));
}

TEST(Progress, DurationsOfAnEta) {
  EXPECT_EQ(formatDuration(0), "0s");
  EXPECT_EQ(formatDuration(42.4), "42s");
  EXPECT_EQ(formatDuration(119), "119s");
  EXPECT_EQ(formatDuration(120), "2.0min");
  EXPECT_EQ(formatDuration(5400), "90.0min");
  EXPECT_EQ(formatDuration(7200), "2.0h");
}

// A run that stops on its probes: two probes whose records start at 0.5 and 1.0 m and last
// 0.05 s after the arrival, a front at 2 m/s. By hand: at t 0.1 s with the front at 0.3 m the far
// probe decides, 0.7 / 2 + 0.05 = 0.4 s; once the near one has its arrival (0.2 s), at 0.22 s with
// the front at 0.6 m: 0.4 / 2 + 0.05 = 0.25 s; both arrived (0.2, 0.45 s), at 0.47 s: 0.03 s.
TEST(Progress, ProbesTimeLeftFromTheFront) {
  std::vector<ProbeProgress> probes{{0.5, 0.05, std::nullopt}, {1.0, 0.05, std::nullopt}};
  EXPECT_NEAR(*probesTimeLeft(0.1, 0.3, 2.0, probes), 0.4, 1e-15);
  probes[0].arrival = 0.2;
  EXPECT_NEAR(*probesTimeLeft(0.22, 0.6, 2.0, probes), 0.25, 1e-15);
  // a front past a station whose probe has not yet its points: the window alone
  EXPECT_NEAR(*probesTimeLeft(0.3, 1.01, 2.0, probes), 0.05, 1e-15);
  // a front that stands still or backs (a surge): no estimate while a probe waits for it
  EXPECT_FALSE(probesTimeLeft(0.22, 0.6, 0.0, probes).has_value());
  EXPECT_FALSE(probesTimeLeft(0.22, 0.6, -0.1, probes).has_value());
  EXPECT_FALSE(probesTimeLeft(0.22, 0.6, NAN, probes).has_value());
  probes[1].arrival = 0.45;
  EXPECT_NEAR(*probesTimeLeft(0.47, 1.1, 0.0, probes), 0.03, 1e-15);
  EXPECT_DOUBLE_EQ(*probesTimeLeft(0.6, 1.2, 0.0, probes), 0.0);  // complete: nothing left
}

TEST(StopSignal, Names) {
  EXPECT_STREQ(signalName(SIGINT), "SIGINT");
  EXPECT_STREQ(signalName(SIGTERM), "SIGTERM");
  EXPECT_STREQ(signalName(SIGHUP), "a signal");
}

// In a process of their own (the handlers and the recorded signal last as long as it does).
TEST(StopSignalDeathTest, ATermIsRecordedAndMoreChangeNothing) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        if (stopSignal() != 0) std::exit(1);
        catchStopSignals();
        std::raise(SIGTERM);
        std::raise(SIGTERM);
        std::exit(stopSignal() == SIGTERM ? 0 : 2);
      },
      testing::ExitedWithCode(0), "");
}

TEST(StopSignalDeathTest, ASecondInterruptEndsTheProcess) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        catchStopSignals();
        std::raise(SIGINT);
        if (stopSignal() != SIGINT) std::exit(2);
        std::raise(SIGINT);
        std::exit(0);
      },
      testing::KilledBySignal(SIGINT), "");
}

// --steps N from a restart point or another run's front: the run stops N steps after the state's
// own step; a state whose step leaves no room for N more (only a file no run wrote can hold one)
// is refused by name, where the sum would have wrapped round to a negative count.
TEST(RunLoop, EndStepCountsFromTheStateAndRefusesAnOverflow) {
  EXPECT_EQ(endStep(1824, 500, "--restart: snapshot 2"), 2324);
  EXPECT_EQ(endStep(0, 1, "x"), 1);
  const long top = std::numeric_limits<long>::max();
  EXPECT_EQ(endStep(top - 5, 5, "x"), top);
  try {
    endStep(top - 4, 5, "--restart: snapshot 3 of out/mpm.h5");
    FAIL() << "an end step past LONG_MAX was accepted";
  } catch (const ParameterError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("--restart: snapshot 3 of out/mpm.h5 is at step " + std::to_string(top - 4)), std::string::npos) << m;
    EXPECT_NE(m.find("--steps 5"), std::string::npos) << m;
  }
  EXPECT_THROW(endStep(-1, 5, "x"), ParameterError);
}
