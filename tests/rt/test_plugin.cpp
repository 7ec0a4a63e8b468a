// Components loaded from shared libraries through the C ABI.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal.hpp"

using namespace truecut::rt::hal;

namespace {
HalOptions opts() {
  HalOptions o;
  o.component_path = {truecut::test::test_component_dir()};
  return o;
}
}  // namespace

TEST(Plugin, LoadsRunsAndUnloadsASharedLibraryComponent) {
  const auto so = truecut::test::test_component_dir() / "test_counter.so";
  // Our own reference keeps the library mapped after the HAL closes it, so
  // the exit counter can still be read.
  void* handle = dlopen(so.c_str(), RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(nullptr, handle) << dlerror();
  auto* exit_calls = static_cast<int*>(dlsym(handle, "test_counter_exit_calls"));
  ASSERT_NE(nullptr, exit_calls);
  const int exits_before = *exit_calls;
  {
    Hal hal(opts());
    hal.new_thread("servo-thread", 1'000'000);
    hal.load("test_counter", {"count=2"});
    EXPECT_TRUE(hal.is_loaded("test_counter"));
    ASSERT_TRUE(hal.has_pin("test_counter.1.count"));
    hal.set_pin_or_param("test_counter.1.step", "5");
    hal.add_function("test_counter.0.update", "servo-thread");
    hal.add_function("test_counter.1.update", "servo-thread");
    Executor ex(hal);
    RunLimits lim;
    lim.max_cycles = 10;
    auto r = ex.run_simulated(lim);
    EXPECT_EQ(10u, r.threads[0].cycles);
    EXPECT_EQ(10, hal.get_pin_or_param("test_counter.0.count").s);
    EXPECT_EQ(50, hal.get_pin_or_param("test_counter.1.count").s);
    EXPECT_EQ(1'000'000, hal.get_pin_or_param("test_counter.0.period-ns").s);
    EXPECT_EQ(exits_before, *exit_calls);
  }
  EXPECT_EQ(exits_before + 1, *exit_calls) << "the HAL calls exit once on teardown";
  dlclose(handle);
}

TEST(Plugin, FailedInitLeavesNothingBehind) {
  Hal hal(opts());
  try {
    hal.load("test_counter", {"fail=1"});
    FAIL();
  } catch (const HalError& e) {
    EXPECT_STREQ(
        "loadrt test_counter: initialisation failed (Input/output error): asked to fail (fail=1)",
        e.what());
  }
  EXPECT_FALSE(hal.is_loaded("test_counter"));
  EXPECT_FALSE(hal.has_pin("test_counter.0.count")) << "pins of a failed load are removed";
  hal.load("test_counter", {});  // and it can be loaded again
  EXPECT_TRUE(hal.has_pin("test_counter.0.count"));
}

TEST(Plugin, LibraryWithoutEntryPointsIsRejected) {
  Hal hal(opts());
  try {
    hal.load("not_a_component", {});
    FAIL();
  } catch (const HalError& e) {
    EXPECT_NE(std::string(e.what()).find("is not a truecut component"), std::string::npos)
        << e.what();
  }
}

TEST(Plugin, UnknownArgumentIsReportedByTheComponent) {
  Hal hal(opts());
  EXPECT_THROW(hal.load("test_counter", {"bogus=1"}), HalError);
  EXPECT_THROW(hal.load("test_counter", {"count=9"}), HalError);
}

TEST(Plugin, AbiTableDescribesItself) {
  const tc_hal_api_t* api = Hal::api();
  EXPECT_EQ(TC_HAL_ABI_VERSION, api->abi_version);
  EXPECT_EQ(sizeof(tc_hal_api_t), api->struct_size);
  EXPECT_EQ(TC_HAL_FLOAT, static_cast<int>(Type::kFloat));
  EXPECT_EQ(32, TC_HAL_OUT) << "LinuxCNC's HAL_OUT value";
}

TEST(Plugin, ComponentNewOutsideLoadrtIsRefused) {
  Hal hal(opts());
  EXPECT_LT(Hal::api()->component_new(hal.state(), "rogue"), 0);
}

// A component that fails to write its output at exit (a full disk) reports
// an error; unload() counts it, so `truecut run` can fail instead of
// reporting a file it never wrote. Once only: the destructor does not call
// the exits again.
namespace {
int writer_exits = 0;
int writer_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  const int id = api->component_new(hal, "writer");
  return id < 0 ? id : api->component_ready(hal, id);
}
void writer_exit(const tc_hal_api_t* api, tc_hal_t* hal, void*) {
  ++writer_exits;
  api->message(hal, TC_HAL_MSG_ERR, "writer: cannot write out.stl: No space left on device");
}
void quiet_exit(const tc_hal_api_t* api, tc_hal_t* hal, void*) {
  api->message(hal, TC_HAL_MSG_INFO, "quiet: wrote nothing");
}
}  // namespace

TEST(Plugin, UnloadCountsTheErrorsComponentsReportWritingTheirFiles) {
  writer_exits = 0;
  {
    Hal hal(opts());
    hal.load("writer", writer_init, writer_exit);
    hal.load(
        "quiet",
        [](const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
          return api->component_ready(hal, api->component_new(hal, "quiet"));
        },
        quiet_exit);
    EXPECT_EQ(1, hal.unload());
    EXPECT_EQ(1, writer_exits);
    EXPECT_EQ(0, hal.unload());  // once only
  }
  EXPECT_EQ(1, writer_exits);  // not again in the destructor
  {
    Hal hal(opts());
    hal.load(
        "quiet",
        [](const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
          return api->component_ready(hal, api->component_new(hal, "quiet"));
        },
        quiet_exit);
    EXPECT_EQ(0, hal.unload());
  }
}
