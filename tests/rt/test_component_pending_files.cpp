// A component's temporary files are the host's to remove on a signal
// (hal_abi.h pending_file_add): a component library has its own copy of
// rt's table of pending files, which the host's signal handler does not see,
// so before this the cutting component's machined.stl.tmp stayed behind when
// a run was ended while it wrote (issue 23, "leaves nothing behind").
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "test_paths.hpp"
#include "truecut/rt/hal.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"

namespace fs = std::filesystem;
using namespace truecut;

namespace {

// How a child that loads test_unload_writer with `args` and unloads it
// ended: the signal, or 0 when it exited.
int unload_in_a_child(const fs::path& out, const std::vector<std::string>& args) {
  const pid_t pid = fork();
  if (pid == 0) {
    rt::remove_pending_files_on_signals();
    rt::hal::HalOptions o;
    o.component_path = {test::test_component_dir()};
    o.output_dir = out;
    rt::hal::Hal h(o);
    h.load("test_unload_writer", args);
    _exit(h.unload() == 0 ? 0 : 3);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) ? WTERMSIG(status) : -WEXITSTATUS(status);
}

std::vector<std::string> g_added;  // paths given to the fake host
std::vector<int> g_done;           // handles it was told are done

int fake_add(tc_hal_t*, const char* path) {
  g_added.emplace_back(path);
  return 40 + static_cast<int>(g_added.size());
}
void fake_done(tc_hal_t*, int handle) {
  g_done.push_back(handle);
}

}  // namespace

TEST(ComponentPendingFiles, AFileAComponentWritesAtUnloadIsRemovedOnASignal) {
  const fs::path out = test::scratch_dir();
  EXPECT_EQ(SIGTERM, unload_in_a_child(out, {"to-host=1", "signal=1"}));
  EXPECT_FALSE(fs::exists(out / "unload.txt.tmp"));
  EXPECT_FALSE(fs::exists(out / "unload.txt"));
}

TEST(ComponentPendingFiles, WithoutTheHostsTableTheComponentsFileStays) {
  // The control: a component that keeps the name in its own copy of the
  // table (as the cutting component did) leaves its half-written file.
  const fs::path out = test::scratch_dir();
  EXPECT_EQ(SIGTERM, unload_in_a_child(out, {"to-host=0", "signal=1"}));
  EXPECT_TRUE(fs::exists(out / "unload.txt.tmp"));
}

TEST(ComponentPendingFiles, AFileWrittenToTheEndIsKeptAndNoLongerTracked) {
  const fs::path out = test::scratch_dir();
  EXPECT_EQ(0, unload_in_a_child(out, {"to-host=1", "signal=0"}));
  EXPECT_TRUE(fs::exists(out / "unload.txt"));
  EXPECT_FALSE(fs::exists(out / "unload.txt.tmp"));
  const std::size_t before = rt::pending_file_count();
  {
    rt::hal::HalOptions o;
    o.component_path = {test::test_component_dir()};
    o.output_dir = out;
    rt::hal::Hal h(o);
    h.load("test_unload_writer", {"to-host=1"});
    EXPECT_EQ(0, h.unload());
  }
  EXPECT_EQ(before, rt::pending_file_count()) << "the host released the name at the rename";
}

TEST(ComponentPendingFiles, TheGuardSendsNamesToTheHostThatHasTheCalls) {
  tc_hal_api_t host = *rt::hal::Hal::api();
  host.pending_file_add = fake_add;
  host.pending_file_done = fake_done;
  g_added.clear();
  g_done.clear();
  const std::size_t before = rt::pending_file_count();
  {
    const rt::PendingFilesToHost to_host(&host, nullptr);
    const rt::PendingFile a("/tmp/a.tmp");
    EXPECT_TRUE(a.tracked());
    EXPECT_EQ(before, rt::pending_file_count()) << "not in this copy's table";
    {
      // A host whose table ends before the two calls: this copy's table.
      tc_hal_api_t older = host;
      older.struct_size = static_cast<uint32_t>(offsetof(tc_hal_api_t, pending_file_add));
      const rt::PendingFilesToHost inner(&older, nullptr);
      const rt::PendingFile b("/tmp/b.tmp");
      EXPECT_EQ(before + 1, rt::pending_file_count());
    }
    const rt::PendingFile c("/tmp/c.tmp");  // the outer host again
    EXPECT_EQ(before, rt::pending_file_count());
  }
  ASSERT_EQ((std::vector<std::string>{"/tmp/a.tmp", "/tmp/c.tmp"}), g_added);
  EXPECT_EQ((std::vector<int>{42, 41}), g_done) << "c then a, each with its own handle";
  const rt::PendingFile d("/tmp/d.tmp");  // no guard: this copy's table
  EXPECT_EQ(before + 1, rt::pending_file_count());
  EXPECT_EQ(2u, g_added.size());
}

TEST(ComponentPendingFiles, TheHostRefusesAnEmptyNameAndForgetsAHandleOnce) {
  const tc_hal_api_t* api = rt::hal::Hal::api();
  ASSERT_TRUE(TC_HAL_API_HAS(api, pending_file_done));
  rt::hal::Hal h;
  // The public Hal hands components its tc_hal_t; a module's init sees it.
  static tc_hal_t* seen = nullptr;
  h.load(
      "probe",
      [](const tc_hal_api_t* a, tc_hal_t* hal, int, const char* const*, void**) {
        seen = hal;
        const int id = a->component_new(hal, "probe");
        a->component_ready(hal, id);
        return 0;
      },
      [](const tc_hal_api_t*, tc_hal_t*, void*) {});
  ASSERT_NE(nullptr, seen);
  EXPECT_EQ(-EINVAL, api->pending_file_add(seen, ""));
  EXPECT_EQ(-EINVAL, api->pending_file_add(seen, nullptr));
  const std::size_t before = rt::pending_file_count();
  const int handle = api->pending_file_add(seen, "/tmp/probe.tmp");
  ASSERT_GE(handle, 0);
  EXPECT_EQ(before + 1, rt::pending_file_count());
  api->pending_file_done(seen, handle);
  api->pending_file_done(seen, handle);  // a second time, and an unknown one: nothing
  api->pending_file_done(seen, handle + 1000);
  EXPECT_EQ(before, rt::pending_file_count());
  const std::string too_long(rt::kMaxPendingPathBytes + 10, 'x');
  EXPECT_EQ(-ENOSPC, api->pending_file_add(seen, too_long.c_str()));
}
