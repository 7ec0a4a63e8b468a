// The cutting HAL component: loads a benchmark part, cuts between the poses
// of successive cycles, reports power and force, writes the machined surface
// on exit; bad part files fail the load naming file and key.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "test_paths.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"
#include "truecut/sim/benchmark_parts.hpp"

using namespace truecut::rt::hal;

namespace {

HalOptions opts(const std::filesystem::path& out) {
  HalOptions o;
  o.component_path = {truecut::test::component_dir()};
  o.output_dir = out;
  return o;
}

std::filesystem::path implant(const std::filesystem::path& dir) {
  const auto part = truecut::sim::make_part(truecut::sim::PartId::kImplant, {2.0, 0.8, 1.0, 2.0});
  truecut::sim::write_part(part, dir / "implant");
  return dir / "implant";
}

}  // namespace

TEST(CuttingComponent, FaceMillsTheShaftTopAndWritesTheMachinedSurface) {
  const auto dir = truecut::test::scratch_dir();
  const auto part = implant(dir);
  {
    Hal hal(opts(dir));
    load_hal_text(hal,
                  "loadrt threads name1=servo period1=1000000\n"
                  "loadrt cutting names=cut out=machined spacing=0.1 nominal=" +
                      (part / "nominal.stl").string() + " part=" + (part / "part.json").string() +
                      "\nsetp cut.tool-radius 2\nsetp cut.tool-flute-length 20\n"
                      "setp cut.spindle-rpm 12000\nsetp cut.enable 1\n"
                      "setp cut.tcp-x -6\nsetp cut.tcp-z 17\nsetp cut.filter-time 0\n"
                      "addf cut.update servo\n",
                  "cut.hal");
    Executor ex(hal);
    ex.step();  // beside the shaft
    EXPECT_FALSE(hal.get_pin_or_param("cut.engaged").b);
    EXPECT_EQ(0.0, hal.get_pin_or_param("cut.removed-mm3").f);
    hal.set_pin_or_param("cut.tcp-x", "6");
    ex.step();  // one cycle across the shaft top: 1.6 × 1.6 × 0.3 mm of allowance
    const double removed = hal.get_pin_or_param("cut.removed-mm3").f;
    EXPECT_NEAR(1.6 * 1.6 * 0.3, removed, 0.01 * 0.768);
    EXPECT_TRUE(hal.get_pin_or_param("cut.engaged").b);
    EXPECT_NEAR(removed / 1e-3, hal.get_pin_or_param("cut.mrr").f, 1e-6);
    const double power_kw = 1800 * (removed / 1e-3) * 1e-6;
    EXPECT_NEAR(power_kw, hal.get_pin_or_param("cut.spindle-power-kw").f, 1e-9);
    const double vc = M_PI * 4 * 12000 / 60;  // mm/s
    EXPECT_NEAR(0.4 * power_kw * 1e6 / vc, hal.get_pin_or_param("cut.force-z").f, 1e-6);
    EXPECT_NEAR(0.0, hal.get_pin_or_param("cut.force-x").f, 1e-9);
    EXPECT_NEAR(17.15, hal.get_pin_or_param("cut.contact-z").f, 1e-6);
    EXPECT_FALSE(hal.get_pin_or_param("cut.fault").b);
    ex.step();  // standing still: nothing more (unfiltered)
    EXPECT_FALSE(hal.get_pin_or_param("cut.engaged").b);
    EXPECT_EQ(removed, hal.get_pin_or_param("cut.removed-mm3").f);
    hal.set_pin_or_param("cut.tool-radius", "-1");
    ex.step();
    EXPECT_TRUE(hal.get_pin_or_param("cut.fault").b);
  }
  const auto stl = dir / "machined" / "machined.stl";
  EXPECT_TRUE(std::filesystem::is_regular_file(stl));
  ASSERT_TRUE(std::filesystem::is_regular_file(stl));
  ASSERT_TRUE(std::filesystem::is_regular_file(dir / "machined" / "machined.ply"));
  const auto mesh = truecut::offline::read_stl(stl);
  double top = -1e9;
  for (const auto& v : mesh.vertices_mm)
    top = std::max(top, v.z());
  EXPECT_NEAR(17.0, top, 1e-5);  // the 0.3 mm allowance is gone
}

TEST(CuttingComponent, RemovalIsFilteredWithTheFilterTime) {
  const auto dir = truecut::test::scratch_dir();
  const auto part = implant(dir);
  Hal hal(opts(dir));
  load_hal_text(hal,
                "loadrt threads name1=servo period1=1000000\n"
                "loadrt cutting nominal=" +
                    (part / "nominal.stl").string() + " part=" + (part / "part.json").string() +
                    "\nsetp cutting.0.tool-radius 2\nsetp cutting.0.tool-flute-length 20\n"
                    "setp cutting.0.spindle-rpm 12000\nsetp cutting.0.enable 1\n"
                    "setp cutting.0.tcp-x -6\nsetp cutting.0.tcp-z 17\n"
                    "addf cutting.0.update servo\n",
                "cut.hal");
  EXPECT_DOUBLE_EQ(0.01, hal.get_pin_or_param("cutting.0.filter-time").f);
  Executor ex(hal);
  ex.step();
  hal.set_pin_or_param("cutting.0.tcp-x", "6");
  ex.step();
  const double removed = hal.get_pin_or_param("cutting.0.removed-mm3").f;
  const double a = 1 - std::exp(-0.1);  // 1 ms period, 10 ms filter
  const double mrr = hal.get_pin_or_param("cutting.0.mrr").f;
  EXPECT_NEAR(a * removed / 1e-3, mrr, 1e-9);
  EXPECT_NEAR(17.15, hal.get_pin_or_param("cutting.0.contact-z").f, 1e-6);
  ex.step();  // nothing removed: the filtered rate decays, the contact stays
  EXPECT_NEAR(mrr * std::exp(-0.1), hal.get_pin_or_param("cutting.0.mrr").f, 1e-9);
  EXPECT_TRUE(hal.get_pin_or_param("cutting.0.engaged").b);
  EXPECT_NEAR(17.15, hal.get_pin_or_param("cutting.0.contact-z").f, 1e-6);
  EXPECT_EQ(removed, hal.get_pin_or_param("cutting.0.removed-mm3").f);
}

TEST(CuttingComponent, BadPartFileFailsTheLoadNamingFileAndKey) {
  const auto dir = truecut::test::scratch_dir();
  const auto part = implant(dir);
  std::string text = truecut::test::read_file(part / "part.json");
  const auto bad = dir / "bad.json";
  {
    std::string t = text;
    t.replace(t.find("\"stock\""), 7, "\"stok\"");
    std::ofstream(bad) << t;
  }
  Hal hal(opts(dir));
  const std::string nominal = "nominal=" + (part / "nominal.stl").string();
  try {
    hal.load("cutting", {nominal, "part=" + bad.string()});
    FAIL() << "loaded";
  } catch (const HalError& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find(bad.string() + ": stock: missing"))
        << e.what();
  }
  EXPECT_FALSE(hal.has_pin("cutting.0.tcp-x")) << "a failed load leaves nothing";
  {
    std::ofstream(bad)
        << "{\"truecut_part\": 1, \"stock\": [{\"min_mm\": [0, 0, 0], \"max_mm\": "
           "[1, 1, 1]}], \"surfaces\": [{\"id\": 1}], \"triangle_surface_ids\": [1]}";
  }
  try {
    hal.load("cutting", {nominal, "part=" + bad.string()});
    FAIL() << "loaded";
  } catch (const HalError& e) {
    EXPECT_NE(std::string::npos,
              std::string(e.what()).find(bad.string() + ": triangle_surface_ids: 1 ids, but"))
        << e.what();
  }
  EXPECT_THROW(hal.load("cutting", {nominal}), HalError);
  EXPECT_THROW(
      hal.load("cutting", {nominal, "part=" + (part / "part.json").string(), "surfaces=1,99"}),
      HalError);
  EXPECT_THROW(hal.load("cutting", {nominal, "part=" + (part / "part.json").string(), "kc=3"}),
               HalError);
}

// The machined part is written at unload through the component's own copy
// of rt, whose table of pending files the host's signal handler does not
// see: its two temporary names must reach the host's table (hal_abi.h
// pending_file_add), and be released at their renames. The component is
// loaded through a copy of the host's function table that records the calls.
namespace {
const tc_hal_api_t* g_host = nullptr;
tc_hal_api_t g_recording_table;
std::vector<std::string> g_pending_added;
int g_pending_done = 0;
tc_component_init_fn g_cutting_init = nullptr;
tc_component_exit_fn g_cutting_exit = nullptr;

int recording_add(tc_hal_t* hal, const char* path) {
  g_pending_added.emplace_back(path);
  return g_host->pending_file_add(hal, path);
}
void recording_done(tc_hal_t* hal, int handle) {
  ++g_pending_done;
  g_host->pending_file_done(hal, handle);
}
int cutting_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc, const char* const* argv,
                 void** state) {
  g_host = api;
  g_recording_table = *api;
  g_recording_table.pending_file_add = recording_add;
  g_recording_table.pending_file_done = recording_done;
  return g_cutting_init(&g_recording_table, hal, argc, argv, state);
}
void cutting_exit(const tc_hal_api_t*, tc_hal_t* hal, void* state) {
  g_cutting_exit(&g_recording_table, hal, state);
}
}  // namespace

TEST(CuttingComponent, ItsTemporaryFilesAreInTheHostsTableWhileItWrites) {
  const auto dir = truecut::test::scratch_dir();
  const auto part = implant(dir);
  const std::string so = (truecut::test::component_dir() / "cutting.so").string();
  void* lib = dlopen(so.c_str(), RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(nullptr, lib) << dlerror();
  g_cutting_init = reinterpret_cast<tc_component_init_fn>(dlsym(lib, TC_COMPONENT_INIT_SYMBOL));
  g_cutting_exit = reinterpret_cast<tc_component_exit_fn>(dlsym(lib, TC_COMPONENT_EXIT_SYMBOL));
  ASSERT_TRUE(g_cutting_init && g_cutting_exit);
  g_pending_added.clear();
  g_pending_done = 0;
  const std::size_t before = truecut::rt::pending_file_count();
  {
    Hal hal(opts(dir));
    hal.new_thread("servo", 1'000'000);
    hal.load("cutting", cutting_init, cutting_exit,
             {"out=cut", "spacing=0.5", "nominal=" + (part / "nominal.stl").string(),
              "part=" + (part / "part.json").string()});
    hal.add_function("cutting.0.update", "servo");
    Executor(hal).step();  // a run of one cycle: its surface is an output
    EXPECT_EQ(0, hal.unload());
  }
  const auto out = std::filesystem::absolute(dir / "cut").lexically_normal();
  EXPECT_EQ((std::vector<std::string>{(out / "machined.stl.tmp").string(),
                                      (out / "machined.ply.tmp").string()}),
            g_pending_added);
  EXPECT_EQ(2, g_pending_done);
  EXPECT_EQ(before, truecut::rt::pending_file_count());
  EXPECT_TRUE(std::filesystem::exists(out / "machined.stl"));
  EXPECT_TRUE(std::filesystem::exists(out / "machined.ply"));
  dlclose(lib);
}

// A HAL whose threads never ran (a dry run, a load refused after this
// component's) has machined nothing: no surface is written, and the
// component says so.
TEST(CuttingComponent, WritesNoSurfaceWhenNoCycleRan) {
  const auto dir = truecut::test::scratch_dir();
  const auto part = implant(dir);
  std::string messages;
  {
    HalOptions o = opts(dir);
    o.message_sink = [&](const std::string& line) { messages += line; };
    Hal hal(o);
    load_hal_text(hal,
                  "loadrt threads name1=servo period1=1000000\n"
                  "loadrt cutting names=cut out=machined spacing=0.5 nominal=" +
                      (part / "nominal.stl").string() + " part=" + (part / "part.json").string() +
                      "\naddf cut.update servo\n",
                  "cut.hal");
    EXPECT_EQ(0, hal.unload());
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "machined" / "machined.stl"));
  EXPECT_FALSE(std::filesystem::exists(dir / "machined" / "machined.ply"));
  EXPECT_NE(std::string::npos,
            messages.find("cut: no cycle ran: machined.stl and machined.ply not written"))
      << messages;
}
