// The truecut HAL shim against LinuxCNC 2.9's own HAL, command by command:
// the same halcmd script runs in `halrun -k` (LinuxCNC's halcmd, carrying on
// after an error) and, line by line, in the shim (rt::hal::load_hal_text),
// and each side's verdict per line (accepted or refused) and every value
// `getp`/`gets` prints must agree. The cases are the rules a HAL file relies
// on: how setp parses each type, what may be written, how net links pins and
// signals, what a signal or pin holds after linking and unlinking, where
// addf puts a function, what may be loaded twice. docs/linuxcnc.md, "The
// shim and LinuxCNC's HAL", lists each rule and where the two differ on
// purpose; those differences are asserted here as differences.
//
// Needs LinuxCNC 2.9 and root, like test_linuxcnc_module.cpp (skipped
// otherwise, failed under TRUECUT_REQUIRE_ORACLES=1).
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "linuxcnc_support.hpp"
#include "oracle.hpp"
#include "run_process.hpp"
#include "test_truecut_comp_support.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut;
using namespace truecut::test;
using rt::hal::Hal;
using rt::hal::Type;

namespace {

// What one side made of a script: the lines it refused, and what each
// getp/gets printed, in order (floats as halcmd prints them, "%.7g").
struct Transcript {
  std::set<int> refused;
  std::vector<std::string> values;
  std::vector<std::string> thread_order;  // functions of thread `t`, from `show thread t`
  std::string log;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

std::string halcmd_text(const rt::hal::Value& v) {
  if (v.type != Type::kFloat) return v.to_text();
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.7g", v.f);
  return buf;
}

Transcript run_shim(const std::string& script) {
  Transcript t;
  Hal hal(comp::hal_options());
  std::istringstream in(script);
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    try {
      if (line.rfind("getp ", 0) == 0) {
        t.values.push_back(halcmd_text(hal.get_pin_or_param(trim(line.substr(5)))));
      } else if (line.rfind("gets ", 0) == 0) {
        t.values.push_back(halcmd_text(hal.get_signal(trim(line.substr(5)))));
      } else if (line.rfind("show thread ", 0) == 0) {
        for (const auto& th : hal.threads())
          if (th.name == trim(line.substr(12))) t.thread_order = th.functions;
      } else {
        rt::hal::load_hal_text(hal, line, "case.hal");
      }
    } catch (const std::exception& e) {
      t.refused.insert(line_no);
      t.log += "case.hal:" + std::to_string(line_no) + ": " + e.what() + "\n";
    }
  }
  return t;
}

// Runs `script` as case.hal in `halrun` (as nobody, in a folder of its own
// named `name`); `keep_going`: halcmd's -k, on past an error.
ProcessResult halrun(const std::string& name, const std::string& script, bool keep_going) {
  const auto work = scratch_dir() / name;
  std::filesystem::create_directories(work);
  ::chmod(work.c_str(), 0777);
  const auto file = work / "case.hal";
  std::ofstream(file) << script;
  std::vector<std::string> command = {"halrun", "-f", file.string()};
  if (keep_going) command.insert(command.begin() + 1, "-k");
  return run_linuxcnc_private(work, command);
}

Transcript run_linuxcnc(const std::string& name, const std::string& script) {
  const ProcessResult r = halrun(name, script, true);
  Transcript t;
  t.log =
      "halrun exit " + std::to_string(r.exit_code) + "\nstdout:\n" + r.out + "\nstderr:\n" + r.err;
  const std::regex error_line("^.*case\\.hal:([0-9]+): .*$");
  const std::regex thread_entry("^ +[0-9]+ (\\S+)$");
  std::smatch m;
  for (const std::string* text : {&r.out, &r.err}) {
    std::istringstream in(*text);
    bool in_threads = false;
    for (std::string line; std::getline(in, line);) {
      if (std::regex_match(line, m, error_line)) {
        t.refused.insert(std::stoi(m[1]));
      } else if (line.rfind("Realtime Threads:", 0) == 0) {
        in_threads = true;
      } else if (in_threads && std::regex_match(line, m, thread_entry)) {
        t.thread_order.push_back(m[1]);
      } else if (text == &r.out && !line.empty() && line.rfind("Note:", 0) != 0 &&
                 line.find("HAL:") == std::string::npos && !in_threads &&
                 line.find(' ') == std::string::npos) {
        t.values.push_back(line);  // getp/gets print the value alone on its line
      } else if (line.empty()) {
        in_threads = false;
      }
    }
  }
  return t;
}

std::string numbered(const std::string& script) {
  std::istringstream in(script);
  std::string out;
  int n = 0;
  for (std::string line; std::getline(in, line);)
    out += std::to_string(++n) + ": " + line + "\n";
  return out;
}

std::string listed(const std::set<int>& s) {
  std::string out;
  for (int v : s)
    out += (out.empty() ? "" : " ") + std::to_string(v);
  return out;
}

// Runs `script` on both sides. The differences kept on purpose are asserted
// as differences: `shim_only_refuses`, lines the shim refuses where LinuxCNC
// accepts (its range checks); `linuxcnc_only_refuses`, lines only the shim
// takes (its extensions). `reloads` are `loadrt` lines of a module already
// loaded: LinuxCNC 2.9's rtapi_app always answers "NAME: already exists",
// but whether halcmd then reports the line as failed races with the
// rtapi_app it starts (on a loaded machine some such lines pass: fresh-clone
// run of 2026-11-27). The shim must refuse them, and LinuxCNC must have
// said "already exists" for each.
void expect_same(const std::string& name, const std::string& script,
                 const std::set<int>& shim_only_refuses = {},
                 const std::set<int>& linuxcnc_only_refuses = {},
                 const std::set<int>& reloads = {}) {
  const Transcript lc = run_linuxcnc(name, script);
  const Transcript shim = run_shim(script);
  std::set<int> expected_shim = lc.refused;
  std::size_t already = 0;
  for (std::size_t at = lc.log.find("already exists"); at != std::string::npos;
       at = lc.log.find("already exists", at + 1))
    ++already;
  EXPECT_GE(already, reloads.size()) << "LinuxCNC no longer says \"already exists\" on a reload\n"
                                     << lc.log;
  for (int line : reloads)
    expected_shim.insert(line);
  for (int line : shim_only_refuses) {
    EXPECT_EQ(0u, lc.refused.count(line))
        << "LinuxCNC now refuses line " << line << " too: the difference is gone\n"
        << lc.log;
    expected_shim.insert(line);
  }
  for (int line : linuxcnc_only_refuses) {
    EXPECT_EQ(1u, lc.refused.count(line)) << "LinuxCNC now takes line " << line << "\n" << lc.log;
    expected_shim.erase(line);
  }
  const std::string context =
      "script:\n" + numbered(script) + "LinuxCNC:\n" + lc.log + "shim:\n" + shim.log;
  EXPECT_EQ(listed(expected_shim), listed(shim.refused)) << "refused lines differ\n" << context;
  EXPECT_EQ(lc.values, shim.values) << "getp/gets values differ\n" << context;
  EXPECT_EQ(lc.thread_order, shim.thread_order) << "thread order differs\n" << context;
}

std::string loads(const std::filesystem::path& field) {
  return "loadrt threads name1=t period1=1000000\n"
         "loadrt truecut_comp names=c field=" +
         field.string() +
         "\n"
         "loadrt siggen\n";
}

struct LinuxcncHal : ::testing::Test {
  void SetUp() override {
    if (const std::string missing = linuxcnc_missing(); !missing.empty())
      TRUECUT_ORACLE_MISSING(missing);
    field = comp::write_field(scratch_dir() / "field.tcf", {});
    ::chmod(scratch_dir().c_str(), 0755);
    ::chmod(field.c_str(), 0644);
  }
  std::filesystem::path field;
};

}  // namespace

// setp and getp on every pin and parameter type: the text each type takes,
// what is written back, and what may not be written at all.
TEST_F(LinuxcncHal, SetpParsesAndRefusesAsHalcmdDoes) {
  const std::string script = loads(field) +
                             "setp c.tool -5\n"                         // 4
                             "getp c.tool\n"                            // 5
                             "setp c.tool 0x10\n"                       // 6
                             "getp c.tool\n"                            // 7
                             "setp c.tool 1.5\n"                        // 8
                             "setp c.tool 12abc\n"                      // 9
                             "setp c.tool 2147483647\n"                 // 10
                             "getp c.tool\n"                            // 11
                             "setp c.tool 2147483648\n"                 // 12
                             "setp c.expect-machine-id 4294967295\n"    // 13
                             "getp c.expect-machine-id\n"               // 14
                             "setp c.expect-machine-id 0x10\n"          // 15
                             "getp c.expect-machine-id\n"               // 16
                             "setp c.expect-machine-id -1\n"            // 17
                             "setp c.expect-machine-id 4294967296\n"    // 18
                             "setp c.enable true\n"                     // 19
                             "getp c.enable\n"                          // 20
                             "setp c.enable 0\n"                        // 21
                             "getp c.enable\n"                          // 22
                             "setp c.enable TRUE\n"                     // 23
                             "getp c.enable\n"                          // 24
                             "setp c.enable FALSE\n"                    // 25
                             "getp c.enable\n"                          // 26
                             "setp c.enable 2\n"                        // 27
                             "setp c.enable yes\n"                      // 28
                             "setp siggen.0.amplitude 0.1\n"            // 29
                             "getp siggen.0.amplitude\n"                // 30
                             "setp siggen.0.amplitude 123456789.123\n"  // 31
                             "getp siggen.0.amplitude\n"                // 32
                             "setp siggen.0.amplitude 1e-300\n"         // 33
                             "getp siggen.0.amplitude\n"                // 34
                             "setp siggen.0.amplitude -0\n"             // 35
                             "getp siggen.0.amplitude\n"                // 36
                             "setp siggen.0.amplitude TRUE\n"           // 37
                             "setp siggen.0.amplitude 1.5x\n"           // 38
                             "setp c.fault 1\n"                         // 39
                             "setp c.update.tmax 5\n"                   // 40
                             "getp c.update.tmax\n"                     // 41
                             "setp c.update.tmax-increased 1\n"         // 42
                             "setp nothing 1\n"                         // 43
                             "getp c.update.tmax-increased\n";          // 44
  // LinuxCNC's halcmd takes s32 and u32 with strtol/strtoul and casts:
  // 2147483648 becomes -2147483648, -1 and 4294967296 wrap. The shim refuses
  // what does not fit.
  expect_same("setp", script, {12, 17, 18});
}

// net, linksp, sets and unlinkp: one writer per signal, one signal per pin,
// matching types, no setp on a linked pin, and the values that pins and
// signals hold across linking and unlinking.
TEST_F(LinuxcncHal, NetLinksAndRefusesAsHalcmdDoes) {
  const std::string script = loads(field) +
                             "setp siggen.0.frequency 2.5\n"        // 4
                             "net f siggen.0.frequency\n"           // 5
                             "gets f\n"                             // 6
                             "getp siggen.0.frequency\n"            // 7
                             "sets f 3\n"                           // 8
                             "getp siggen.0.frequency\n"            // 9
                             "setp siggen.0.frequency 4\n"          // 10
                             "unlinkp siggen.0.frequency\n"         // 11
                             "getp siggen.0.frequency\n"            // 12
                             "setp siggen.0.frequency 4\n"          // 13
                             "getp siggen.0.frequency\n"            // 14
                             "net a siggen.0.sine => c.tcp-x\n"     // 15
                             "sets a 3\n"                           // 16
                             "net b siggen.0.sine\n"                // 17
                             "net a c.tool\n"                       // 18
                             "net a2 siggen.0.cosine => c.tcp-z\n"  // 19
                             "net a2 siggen.0.triangle\n"           // 20
                             "newsig q float\n"                     // 21
                             "newsig q bit\n"                       // 22
                             "newsig r s32\n"                       // 23
                             "sets r 7\n"                           // 24
                             "gets r\n"                             // 25
                             "setp c.tool 16\n"                     // 26
                             "linksp r c.tool\n"                    // 27
                             "getp c.tool\n"                        // 28
                             "gets r\n"                             // 29
                             "newsig uu u32\n"                      // 30
                             "sets uu 4294967295\n"                 // 31
                             "gets uu\n"                            // 32
                             "linkps c.expect-machine-id uu\n"      // 33
                             "getp c.expect-machine-id\n"           // 34
                             "sets nothing 1\n"                     // 35
                             "unlinkp c.nothing\n"                  // 36
                             "net e siggen.0.clock => c.enable\n"   // 37
                             "net e2 c.enable\n"                    // 38
                             "net e c.reset\n"                      // 39
                             "net z siggen.0.square => c.fault\n"   // 40
                             "net y c.tcp-y siggen.0.sawtooth\n"    // 41
                             "getp c.tcp-y\n";                      // 42
  expect_same("net", script);
}

// Functions and threads: addf positions, a function in two threads, a
// second load of the same module, and threads made by `loadrt threads`.
TEST_F(LinuxcncHal, AddfAndLoadrtAsHalcmdDo) {
  const std::string script = loads(field) +
                             "loadrt threads name1=u period1=2000000\n"  // 4
                             "addf siggen.0.update t\n"                  // 5
                             "addf c.update t 1\n"                       // 6
                             "addf c.update t\n"                         // 7
                             "addf c.update u\n"                         // 8
                             "addf nothing t\n"                          // 9
                             "addf siggen.0.update nothing\n"            // 10
                             "loadrt siggen\n"                           // 11
                             "loadrt truecut_comp names=d field=" +
                             field.string() +
                             "\n"                                                    // 12
                             "loadrt truecut_comp names=e field=/nonexistent.tcf\n"  // 13
                             "addf d.update t 2\n"                                   // 14
                             "loadrt threads name1=u period1=2000000\n"              // 15
                             "newthread v 2000000 fp\n"                              // 16
                             "show thread t\n";                                      // 17
  // newthread is the shim's: LinuxCNC 2.9's halcmd does not know it.
  expect_same("addf", script, {}, {16}, {4, 11, 12, 13, 15});
}

namespace {
// "pin|param type dir name" of every pin and parameter.
std::set<std::string> listing_of(const Hal& hal) {
  std::set<std::string> out;
  for (const auto& p : hal.pins())
    out.insert(std::string("pin ") + to_string(p.type) + " " + to_string(p.dir) + " " + p.name);
  for (const auto& p : hal.params())
    out.insert(std::string("param ") + to_string(p.type) + " " + to_string(p.dir) + " " + p.name);
  return out;
}
}  // namespace

// `show pin` and `show param`: the same pins and parameters, with the same
// types and directions, for components, functions and threads. The shim's
// threads have two pins more, `.overruns` and `.cycles`.
TEST_F(LinuxcncHal, PinsAndParametersListAsHalcmdShows) {
  const std::string script = loads(field) + "addf c.update t\nshow pin\nshow param\n";
  const ProcessResult r = halrun("listing", script, false);
  ASSERT_EQ(0, r.exit_code) << r.out << r.err;
  std::set<std::string> lc;
  std::string section;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("Component Pins:", 0) == 0) section = "pin";
    if (line.rfind("Parameters:", 0) == 0) section = "param";
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string t; words >> t;)
      w.push_back(t);
    if (section.empty() || w.size() != 5 || w[0] == "Owner") continue;
    lc.insert(section + " " + w[1] + " " + w[2] + " " + w[4]);
  }
  ASSERT_FALSE(lc.empty()) << r.out;

  Hal hal(comp::hal_options());
  rt::hal::load_hal_text(hal, loads(field) + "addf c.update t\n", "case.hal");
  std::set<std::string> shim = listing_of(hal);
  for (const char* extra : {"pin u32 OUT t.overruns", "pin u32 OUT t.cycles"}) {
    EXPECT_EQ(1u, shim.count(extra)) << extra;
    EXPECT_EQ(0u, lc.count(extra)) << extra;
    shim.erase(extra);
  }
  EXPECT_EQ(lc, shim) << r.out;
}
