// The components truecut ships: siggen, recorder (built in), pos_loop (.so).
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <thread>

#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;

namespace {

HalOptions opts(const std::filesystem::path& out) {
  HalOptions o;
  o.component_path = {truecut::test::component_dir()};
  o.output_dir = out;
  return o;
}

void run_cycles(Hal& hal, uint64_t n) {
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = n;
  ex.run_simulated(lim);
}

std::vector<std::vector<double>> read_csv(const std::filesystem::path& f, std::string* header) {
  std::istringstream in(truecut::test::read_file(f));
  std::string line;
  std::getline(in, *header);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ','))
      row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST(Siggen, WaveformsAtAQuarterPeriod) {
  Hal hal(opts("."));
  load_hal_text(hal,
                "loadrt threads name1=t period1=1000000\nloadrt siggen\n"
                "setp siggen.0.amplitude 2\nsetp siggen.0.offset 1\n"
                "setp siggen.0.frequency 1\naddf siggen.0.update t\n",
                "s.hal");
  run_cycles(hal, 250);  // phase 0.25
  EXPECT_NEAR(3.0, hal.get_pin_or_param("siggen.0.sine").f, 1e-12);
  EXPECT_NEAR(1.0, hal.get_pin_or_param("siggen.0.cosine").f, 1e-12);
  EXPECT_NEAR(1.0, hal.get_pin_or_param("siggen.0.triangle").f, 1e-12);  // 4*0.25-1 = 0
  EXPECT_NEAR(0.0, hal.get_pin_or_param("siggen.0.sawtooth").f, 1e-12);  // 2*0.25-1 = -0.5
  EXPECT_NEAR(3.0, hal.get_pin_or_param("siggen.0.square").f, 1e-12);
  EXPECT_TRUE(hal.get_pin_or_param("siggen.0.clock").b);
}

// Issue 23: a frequency of 1e308 Hz recorded -nan in every output, exit 0.
TEST(Siggen, AHugeFrequencyKeepsEveryOutputFinite) {
  Hal hal(opts("."));
  load_hal_text(hal,
                "loadrt threads name1=t period1=1000000\nloadrt siggen\n"
                "setp siggen.0.frequency 1e308\nsetp siggen.0.amplitude 1e300\n"
                "addf siggen.0.update t\n",
                "s.hal");
  run_cycles(hal, 3);
  for (const char* pin : {"sine", "cosine", "triangle", "sawtooth", "square"})
    EXPECT_TRUE(std::isfinite(hal.get_pin_or_param(std::string("siggen.0.") + pin).f)) << pin;
}

TEST(PosLoop, SteadyStateFollowingErrorIsVelocityOverKv) {
  Hal hal(opts("."));
  // A ramp of 100 mm/s from siggen's sawtooth (amplitude 1000 mm at 0.05 Hz
  // gives 2*1000*0.05 = 100 mm/s).
  load_hal_text(hal,
                "loadrt threads name1=t period1=1000000\nloadrt siggen\nloadrt pos_loop count=2\n"
                "setp siggen.0.amplitude 1000\nsetp siggen.0.frequency 0.05\n"
                "setp pos_loop.0.kv 25\nsetp pos_loop.1.kv 25\nsetp pos_loop.1.ff1 1\n"
                "setp pos_loop.0.encoder-resolution 0\nsetp pos_loop.1.encoder-resolution 0\n"
                "net ramp siggen.0.sawtooth => pos_loop.0.pos-cmd pos_loop.1.pos-cmd\n"
                "addf siggen.0.update t\naddf pos_loop.0.update t\naddf pos_loop.1.update t\n",
                "p.hal");
  run_cycles(hal, 2000);
  EXPECT_NEAR(100.0 / 25.0, hal.get_pin_or_param("pos_loop.0.f-error").f, 1e-6);
  EXPECT_NEAR(100.0, hal.get_pin_or_param("pos_loop.0.vel-fb").f, 1e-6);
  EXPECT_NEAR(0.0, hal.get_pin_or_param("pos_loop.1.f-error").f, 1e-6)
      << "full velocity feed-forward removes the lag";
}

TEST(PosLoop, EncoderQuantisesTheFeedback) {
  Hal hal(opts("."));
  load_hal_text(hal,
                "loadrt threads name1=t period1=1000000\nloadrt siggen\nloadrt pos_loop\n"
                "setp siggen.0.amplitude 3.3\nsetp pos_loop.0.encoder-resolution 0.01\n"
                "net c siggen.0.sine => pos_loop.0.pos-cmd\n"
                "addf siggen.0.update t\naddf pos_loop.0.update t\n",
                "p.hal");
  run_cycles(hal, 137);
  double fb = hal.get_pin_or_param("pos_loop.0.pos-fb").f;
  double tru = hal.get_pin_or_param("pos_loop.0.pos-true").f;
  EXPECT_NEAR(0.0, std::remainder(fb, 0.01), 1e-12);
  EXPECT_LE(std::abs(fb - tru), 0.005 + 1e-12);
}

TEST(PosLoop, AccelerationLimitHolds) {
  auto dir = truecut::test::scratch_dir();
  {
    Hal h2(opts(dir));
    load_hal_text(h2,
                  "loadrt threads name1=t period1=1000000\nloadrt siggen\nloadrt pos_loop\n"
                  "loadrt recorder file=v.csv columns=v\n"
                  "setp siggen.0.amplitude 10\nsetp siggen.0.frequency 2\n"
                  "setp pos_loop.0.max-accel 800\n"
                  "net c siggen.0.square => pos_loop.0.pos-cmd\n"
                  "net v pos_loop.0.vel-fb => recorder.0.v\n"
                  "addf siggen.0.update t\naddf pos_loop.0.update t\naddf recorder.0.sample t\n",
                  "p.hal");
    run_cycles(h2, 1000);
  }
  std::string header;
  auto rows = read_csv(dir / "v.csv", &header);
  ASSERT_EQ(1000u, rows.size());
  double worst = 0;
  for (size_t i = 1; i < rows.size(); ++i)
    worst = std::max(worst, std::abs(rows[i][1] - rows[i - 1][1]) / 0.001);
  EXPECT_LE(worst, 800.0 * (1 + 1e-9));
  EXPECT_GT(worst, 700.0) << "the square wave must actually hit the limit";
}

TEST(Recorder, WritesHeaderTimeAndTypedColumnsThenRenames) {
  auto dir = truecut::test::scratch_dir();
  {
    Hal hal(opts(dir));
    load_hal_text(hal,
                  "loadrt threads name1=t period1=250000\nloadrt siggen\n"
                  "loadrt recorder file=r.csv columns=s,c:bit every=2\n"
                  "net s siggen.0.sine => recorder.0.s\nnet c siggen.0.clock => recorder.0.c\n"
                  "addf siggen.0.update t\naddf recorder.0.sample t\n",
                  "r.hal");
    run_cycles(hal, 10);
    EXPECT_EQ(5u, hal.get_pin_or_param("recorder.0.samples").u);
    EXPECT_EQ(0u, hal.get_pin_or_param("recorder.0.overruns").u);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "r.csv.tmp"));
  std::string header;
  auto rows = read_csv(dir / "r.csv", &header);
  EXPECT_EQ("t,s,c", header);
  ASSERT_EQ(5u, rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_DOUBLE_EQ(double(i) * 0.0005, rows[i][0]);
    EXPECT_TRUE(rows[i][2] == 0.0 || rows[i][2] == 1.0);
  }
}

// Components' messages go to HalOptions::message_sink when one is given
// (truecut run writes them below its progress line), info messages not at
// all with show_info_messages false (--quiet); warnings and errors always.
TEST(Recorder, ItsMessagesGoWhereTheHalOptionsSay) {
  auto dir = truecut::test::scratch_dir();
  for (const bool info : {true, false}) {
    std::vector<std::string> lines;
    {
      HalOptions o = opts(dir);
      o.show_info_messages = info;
      o.message_sink = [&lines](const std::string& line) { lines.push_back(line); };
      Hal hal(o);
      load_hal_text(hal,
                    "loadrt threads name1=t period1=1000000\nloadrt siggen\n"
                    "loadrt recorder file=m.csv columns=s\n"
                    "net s siggen.0.sine => recorder.0.s\n"
                    "addf siggen.0.update t\naddf recorder.0.sample t\n",
                    "m.hal");
      run_cycles(hal, 3);
    }
    if (info) {
      ASSERT_EQ(lines.size(), 1u);
      EXPECT_EQ(lines[0],
                "hal: info: recorder.0: wrote 3 samples to " + (dir / "m.csv").string() + "\n");
    } else {
      EXPECT_TRUE(lines.empty()) << lines.front();
    }
  }
}

TEST(Recorder, DisabledOrNeverRunWritesNoFile) {
  auto dir = truecut::test::scratch_dir();
  {
    Hal hal(opts(dir));
    load_hal_text(hal,
                  "loadrt threads name1=t period1=1000000\n"
                  "loadrt recorder file=never.csv columns=a\naddf recorder.0.sample t\n",
                  "r.hal");
  }
  {
    Hal hal(opts(dir));
    load_hal_text(hal,
                  "loadrt threads name1=t period1=1000000\n"
                  "loadrt recorder file=off.csv columns=a\nsetp recorder.0.enable 0\n"
                  "addf recorder.0.sample t\n",
                  "r.hal");
    run_cycles(hal, 5);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(Recorder, FullQueueDropsAndCounts) {
  auto dir = truecut::test::scratch_dir();
  Hal hal(opts(dir));
  load_hal_text(hal,
                "loadrt threads name1=t period1=1000000\n"
                "loadrt recorder file=q.csv columns=a depth=16\naddf recorder.0.sample t\n",
                "r.hal");
  Executor ex(hal);
  for (int i = 0; i < 40; ++i)
    ex.step();  // no services: nothing drains
  EXPECT_EQ(40u, hal.get_pin_or_param("recorder.0.samples").u +
                     hal.get_pin_or_param("recorder.0.overruns").u);
  EXPECT_GT(hal.get_pin_or_param("recorder.0.overruns").u, 0u);
}

// issue 23: `truecut run CONFIG.hal` without --time or --cycles recorded
// until the disk was full. The trace stops at max-mb, whole lines only, the
// run is asked to stop, and the unload reports an error naming the limit.
TEST(Recorder, ATraceStopsAtItsSizeLimitAndTheRunWithIt) {
  auto dir = truecut::test::scratch_dir();
  std::vector<std::string> lines;
  RunReport report;
  int unload_errors = 0;
  {
    HalOptions o = opts(dir);
    o.message_sink = [&lines](const std::string& line) { lines.push_back(line); };
    Hal hal(o);
    load_hal_text(hal,
                  "loadrt threads name1=t period1=1000000\nloadrt siggen\n"
                  "loadrt recorder file=big.csv columns=s,c max-mb=1\n"
                  "net s siggen.0.sine => recorder.0.s\nnet c siggen.0.cosine => recorder.0.c\n"
                  "addf siggen.0.update t\naddf recorder.0.sample t\n",
                  "big.hal");
    Executor ex(hal);
    RunLimits lim;
    lim.max_cycles = 10'000'000;
    report = ex.run_simulated(lim);
    unload_errors = hal.unload();
  }
  EXPECT_TRUE(report.stopped_by_request);
  ASSERT_EQ(1u, report.threads.size());
  EXPECT_LT(report.threads[0].cycles, 100'000u) << "stopped soon after the limit";
  EXPECT_EQ(1, unload_errors);
  const std::string text = truecut::test::read_file(dir / "big.csv");
  EXPECT_LE(text.size(), 1'000'000u);
  EXPECT_GT(text.size(), 1'000'000u - 100) << "filled up to the last whole line";
  ASSERT_EQ('\n', text.back());
  std::string header;
  const auto rows = read_csv(dir / "big.csv", &header);
  for (const auto& row : rows)
    ASSERT_EQ(3u, row.size());
  ASSERT_FALSE(lines.empty());
  const std::string& last = lines.back();
  EXPECT_NE(std::string::npos, last.find("error: recorder.0: " + (dir / "big.csv").string() +
                                         " reached its size limit max-mb=1 (MB)"))
      << last;
  EXPECT_NE(std::string::npos, last.find("max-mb=N raises the limit")) << last;
  char t[32];
  std::snprintf(t, sizeof t, "%.6g", rows.back()[0]);
  EXPECT_NE(std::string::npos, last.find(std::string("ends at t = ") + t + " s")) << last;
}

TEST(Recorder, AMaximumSizeOutsideItsRangeFailsTheLoad) {
  auto dir = truecut::test::scratch_dir();
  for (const char* bad : {"max-mb=0", "max-mb=-5", "max-mb=2e3", "max-mb=1099511627777"}) {
    Hal hal(opts(dir));
    try {
      load_hal_text(hal,
                    std::string("loadrt threads name1=t period1=1000000\n"
                                "loadrt recorder file=x.csv columns=a ") +
                        bad + "\n",
                    "x.hal");
      ADD_FAILURE() << bad << " loaded";
    } catch (const HalFileError& e) {
      EXPECT_NE(std::string::npos, std::string(e.what()).find("max-mb")) << e.what();
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "x.csv.tmp"));
}

TEST(Recorder, BadColumnsAreRejected) {
  Hal hal(opts("."));
  EXPECT_THROW(hal.load("recorder", {"file=a.csv", "columns=a,,b"}), HalError);
  EXPECT_THROW(hal.load("recorder", {"file=a.csv", "columns=a:double"}), HalError);
  EXPECT_THROW(hal.load("recorder", {"file=a.csv", "columns=a,a"}), HalError);
  EXPECT_THROW(hal.load("recorder", {"file=a.csv", "columns=t"}), HalError);
}

// Issue 23: 100,000 names took 22 s before "at most 64 columns": every name
// was compared with those before it first. The count comes first now, so
// even a repeated name among too many columns is refused for the count.
TEST(Recorder, TooManyColumnsAreCountedBeforeNamesAreCompared) {
  Hal hal(opts(truecut::test::scratch_dir()));
  std::string columns = "a,a";
  for (int i = 0; i < 63; ++i)
    columns += ",c" + std::to_string(i);
  try {
    hal.load("recorder", {"file=a.csv", "columns=" + columns});
    FAIL() << "65 columns were taken";
  } catch (const HalError& e) {
    EXPECT_NE(std::string::npos,
              std::string(e.what()).find("columns= lists 65 columns, at most 64"))
        << e.what();
  }
}

TEST(Recorder, DeviceOrFifoIsWrittenDirectlyAndNeverReplaced) {
  auto dir = truecut::test::scratch_dir();
  const auto fifo = dir / "trace.fifo";
  ASSERT_EQ(0, mkfifo(fifo.c_str(), 0600));
  std::string received;
  std::thread reader([&] { received = truecut::test::read_file(fifo); });
  {
    Hal hal(opts(dir));
    load_hal_text(hal,
                  "loadrt threads name1=t period1=1000000\nloadrt siggen\n"
                  "loadrt recorder file=trace.fifo columns=s\n"
                  "net s siggen.0.sine => recorder.0.s\n"
                  "addf siggen.0.update t\naddf recorder.0.sample t\n",
                  "r.hal");
    run_cycles(hal, 3);
  }
  reader.join();
  EXPECT_TRUE(std::filesystem::is_fifo(fifo)) << "the FIFO must not be replaced by a file";
  EXPECT_FALSE(std::filesystem::exists(dir / "trace.fifo.tmp"));
  EXPECT_EQ(0u, received.find("t,s\n0,"));
  EXPECT_EQ(4, std::count(received.begin(), received.end(), '\n'));
}
