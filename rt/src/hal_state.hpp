// Internal: the HAL's data structures, shared by the HAL, the component ABI
// trampolines and the executor. Objects are held by unique_ptr so their
// addresses stay fixed: pins point into signals, components point at pins.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "truecut/rt/hal.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"

namespace truecut::rt::hal::detail {

// Storage of a pin or signal; pins point at `f`, `s`, `u` or `b` through the
// component's pointer, all of which share the union's address.
union Data {
  bool b;
  double f;
  int32_t s;
  uint32_t u;
};

struct Signal;

struct Pin {
  std::string name;
  Type type;
  PinDir dir;
  int comp_id;
  void** data_ptr_addr;  // the component's pointer that the HAL aims
  Data dummy{};          // the pin's own value while unlinked
  Signal* signal = nullptr;
};

struct Param {
  std::string name;
  Type type;
  ParamDir dir;
  int comp_id;
  void* data;
};

struct Signal {
  std::string name;
  Type type;
  Data data{};
  int writers = 0;
  int bidirs = 0;
  int readers = 0;
};

struct Funct {
  std::string name;
  int comp_id;
  tc_hal_funct_t fn;
  void* arg;
  bool uses_fp;
  std::string thread;  // empty until addf
  // LinuxCNC 2.9's timing pin <funct>.time and parameters .tmax (rw) and
  // .tmax-increased (ro). The pin pointer is aimed by the HAL like any
  // component's.
  void* time_pin = nullptr;  // s32, ns
  bool tmax_increased = false;
  int32_t tmax_ns = 0;
};

struct Thread {
  std::string name;
  int64_t period_ns;
  bool uses_fp;
  std::vector<Funct*> functs;
  void* time_pin = nullptr;      // s32 <thread>.time: compute time of the last cycle, ns
  void* overruns_pin = nullptr;  // u32 <thread>.overruns
  void* cycles_pin = nullptr;    // u32 <thread>.cycles (wraps)
  int32_t tmax_ns = 0;           // param <thread>.tmax
};

struct Component {
  int id;
  std::string name;
  std::string module;
  bool ready = false;
};

struct Service {
  int comp_id;
  tc_hal_service_t fn;
  void* arg;
  bool background = false;  // background_service_new: its own thread on the wall clock
};

struct Module {
  std::string name;
  void* dl_handle = nullptr;  // null for built-ins
  tc_component_exit_fn exit = nullptr;
  void* state = nullptr;
};

}  // namespace truecut::rt::hal::detail

struct tc_hal {
  truecut::rt::hal::HalOptions options;
  std::string output_dir_text;
  int next_comp_id = 1;
  std::string loading_module;  // set while a module's init runs
  std::string load_error;      // set_error() text of the module being loaded
  std::vector<std::unique_ptr<truecut::rt::hal::detail::Component>> components;
  std::map<std::string, std::unique_ptr<truecut::rt::hal::detail::Pin>> pins;
  std::map<std::string, std::unique_ptr<truecut::rt::hal::detail::Param>> params;
  std::map<std::string, std::unique_ptr<truecut::rt::hal::detail::Signal>> signals;
  std::map<std::string, std::unique_ptr<truecut::rt::hal::detail::Funct>> functs;
  std::vector<std::unique_ptr<truecut::rt::hal::detail::Thread>> threads;  // creation order
  std::vector<truecut::rt::hal::detail::Service> services;
  std::vector<truecut::rt::hal::detail::Module> modules;  // load order
  std::vector<std::unique_ptr<unsigned char[]>> allocations;
  std::atomic<bool> stop{false};
  std::atomic<int> error_messages{0};   // api_message calls at TC_HAL_MSG_ERR (any thread)
  bool unloaded = false;                // the modules' exit functions have run
  bool threads_loaded = false;          // `loadrt threads` ran (LinuxCNC loads it once)
  std::atomic<bool> cycles_ran{false};  // a thread has run a cycle (api cycles_ran)
  // Components' temporary files (pending_file_add), removed on a signal by
  // this process's handler; registered from exit or from any service thread.
  std::mutex pending_files_mutex;
  std::map<int, std::unique_ptr<truecut::rt::PendingFile>> pending_files;
  int next_pending_file = 0;

  truecut::rt::hal::detail::Component* component(int id) const;
  truecut::rt::hal::detail::Thread* thread(const std::string& name) const;
  // Creates a pin or parameter; throws HalError (duplicate name, bad comp).
  void add_pin(int comp_id, const std::string& name, truecut::rt::hal::Type type,
               truecut::rt::hal::PinDir dir, void** data_ptr_addr);
  void add_param(int comp_id, const std::string& name, truecut::rt::hal::Type type,
                 truecut::rt::hal::ParamDir dir, void* data);
};
