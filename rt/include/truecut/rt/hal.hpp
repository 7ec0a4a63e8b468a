// The HAL: components, pins, parameters, signals, functions and threads with
// LinuxCNC's semantics. Everything here is set-up (non-real-time) API; the
// servo cycle itself runs in truecut::rt::hal::Executor.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "truecut/rt/hal_abi.h"

struct tc_hal;  // the HAL's state; also the opaque handle components see

namespace truecut::rt::hal {

enum class Type { kBit = TC_HAL_BIT, kFloat = TC_HAL_FLOAT, kS32 = TC_HAL_S32, kU32 = TC_HAL_U32 };
enum class PinDir { kIn = TC_HAL_IN, kOut = TC_HAL_OUT, kIo = TC_HAL_IO };
enum class ParamDir { kRo = TC_HAL_RO, kRw = TC_HAL_RW };

const char* to_string(Type type);
const char* to_string(PinDir dir);
const char* to_string(ParamDir dir);

// A typed value as it sits in a pin, parameter or signal.
struct Value {
  Type type = Type::kFloat;
  union {
    bool b;
    double f;
    int32_t s;
    uint32_t u;
  };
  Value() : f(0.0) {}
  static Value of_bit(bool v);
  static Value of_float(double v);
  static Value of_s32(int32_t v);
  static Value of_u32(uint32_t v);
  double as_double() const;
  // As halcmd's getp prints it, except floats, which keep every digit
  // (shortest round trip) where halcmd prints "%.7g".
  std::string to_text() const;
};

// Parses `text` as a value of `type` the way halcmd's setp does (bit: 0, 1,
// TRUE, FALSE; numbers must be consumed whole, s32/u32 range-checked).
// Throws HalError naming the text and the type.
Value parse_value(Type type, const std::string& text);

// Threads one HAL may have (LinuxCNC's RTAPI_MAX_TASKS): each costs a few
// MB (its latency record and executor state), and no machine needs more.
constexpr std::size_t kMaxThreads = 64;

class HalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct HalOptions {
  // Folders searched, in order, for `NAME.so` when `loadrt NAME` is not a built-in.
  std::vector<std::filesystem::path> component_path;
  // Where components write their files (recorder traces, ...).
  std::filesystem::path output_dir = ".";
  // Components' info messages on stderr; false (--quiet): warnings and
  // errors only.
  bool show_info_messages = true;
  // Where the messages go, one line each with its "\n" ("cut: info: ...");
  // empty: stderr. Called from whichever thread the component calls from.
  std::function<void(const std::string& line)> message_sink;
};

struct PinInfo {
  std::string name;
  Type type;
  PinDir dir;
  std::string owner;   // component name
  std::string signal;  // empty when unlinked
};
struct ParamInfo {
  std::string name;
  Type type;
  ParamDir dir;
  std::string owner;
};
struct SignalInfo {
  std::string name;
  Type type;
  int writers;  // out pins
  int bidirs;   // io pins
  int readers;  // in pins
};
struct ThreadInfo {
  std::string name;
  int64_t period_ns;
  bool uses_fp;
  std::vector<std::string> functions;  // in execution order
};

class Hal {
 public:
  explicit Hal(HalOptions options = {});
  ~Hal();  // calls every module's exit, last loaded first (unless unload() did)
  // Calls every module's exit now, last loaded first (components write
  // their files there); returns how many errors they reported doing so.
  // Once only: later calls, and the destructor, do nothing more.
  int unload();
  Hal(const Hal&) = delete;
  Hal& operator=(const Hal&) = delete;

  // `loadrt module arg...`; `threads` is the built-in thread creator
  // (name1=... period1=... [fp1=0|1], up to 9 threads).
  void load(const std::string& module, const std::vector<std::string>& args);
  // Loads a component whose entry points the caller already has (an
  // application embedding truecut, or a test), exactly as loadrt would.
  void load(const std::string& module, tc_component_init_fn init, tc_component_exit_fn exit,
            const std::vector<std::string>& args = {});
  bool is_loaded(const std::string& module) const;

  // `newthread name period_ns [fp|nofp]`
  void new_thread(const std::string& name, int64_t period_ns, bool uses_fp = true);
  // `addf funct thread [position]`: position 1 = first, -1 = last (default),
  // counting as LinuxCNC does.
  void add_function(const std::string& funct, const std::string& thread, int position = -1);

  // `newsig name type`
  void new_signal(const std::string& name, Type type);
  // Links a pin to a signal (creating the signal with the pin's type when it
  // does not exist). Enforces one writer per signal, matching types, one
  // signal per pin.
  void link(const std::string& pin, const std::string& signal);
  void unlink(const std::string& pin);

  // `setp`: parameters (rw) and unlinked in/io pins. `sets`: signals without
  // a writer.
  void set_pin_or_param(const std::string& name, const std::string& value_text);
  void set_signal(const std::string& name, const std::string& value_text);
  // `getp`/`gets`
  Value get_pin_or_param(const std::string& name) const;
  Value get_signal(const std::string& name) const;

  bool has_pin(const std::string& name) const;
  bool has_param(const std::string& name) const;
  bool has_signal(const std::string& name) const;
  bool has_function(const std::string& name) const;
  bool has_thread(const std::string& name) const;

  std::vector<PinInfo> pins() const;
  std::vector<ParamInfo> params() const;
  std::vector<SignalInfo> signals() const;
  std::vector<ThreadInfo> threads() const;
  std::vector<std::string> functions() const;

  // Real-time safe and async-signal safe.
  void request_stop() noexcept;
  bool stop_requested() const noexcept;
  void clear_stop() noexcept;

  // Runs the components' non-real-time services once, in registration order:
  // all of them (simulated time, set-up, tests), or only the ordinary ones or
  // only the background ones (the wall clock runs these in their own thread).
  enum class Services { kAll, kForeground, kBackground };
  void run_services(Services which = Services::kAll);
  std::size_t service_count(Services which = Services::kAll) const;

  const HalOptions& options() const;
  // The C function table handed to components.
  static const tc_hal_api_t* api();
  tc_hal* state() { return state_.get(); }
  const tc_hal* state() const { return state_.get(); }

 private:
  std::unique_ptr<tc_hal> state_;
};

// Built-in components (compiled into truecut) that `loadrt` finds by name
// before searching shared libraries.
struct BuiltinComponent {
  const char* name;
  tc_component_init_fn init;
  tc_component_exit_fn exit;
};
const std::vector<BuiltinComponent>& builtin_components();

}  // namespace truecut::rt::hal
