// The truecut HAL component ABI (truecut/rt/hal_abi.h) on top of LinuxCNC's
// own HAL, so a component written for the truecut shim builds, unchanged, as
// a LinuxCNC 2.9 uspace module. rtapi_app_main() creates the LinuxCNC
// component (named after the module, as halcmd's loadrt expects), turns the
// module parameters back into the "key=value" arguments the component
// parses, calls truecut_component_init() with a function table that maps to
// hal_pin_new(), hal_export_funct(), hal_malloc() and friends, and starts a
// non-real-time thread for the component's services. rtapi_app_exit() stops
// that thread, runs the services once more and calls truecut_component_exit().
//
// One difference has to be bridged: LinuxCNC keeps the address of each pin's
// pointer and requires it to lie in HAL shared memory (halcmd, another
// process, rewrites it on `net`), while the truecut ABI lets the component
// keep its pin pointers anywhere. The adapter therefore gives LinuxCNC a
// pointer slot in shared memory for each pin and, before each of the
// component's functions runs, copies the slots into the component's own
// pointers (a few dozen pointer copies; nothing allocated, nothing locked).
//
// Compiled with the flags halcompile uses for uspace modules (see
// cmake/TruecutLinuxcnc.cmake); the module's name comes from
// TRUECUT_LINUXCNC_MODULE.
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hal.h"
#include "rtapi.h"
#include "rtapi_app.h"
#include "truecut/rt/hal_abi.h"

#ifndef TRUECUT_LINUXCNC_MODULE
#error "TRUECUT_LINUXCNC_MODULE must name the module"
#endif

extern "C" int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc,
                                      const char* const* argv, void** module_state);
extern "C" void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal, void* module_state);

MODULE_AUTHOR("truecut");
MODULE_DESCRIPTION("truecut compensation component (truecut HAL ABI on LinuxCNC HAL)");
MODULE_LICENSE("GPL");

// The component's loadrt arguments. rtapi_app sets only those given; the
// adapter passes exactly those on, so the component sees the same argument
// list as under the truecut shim.
static char* field = nullptr;
RTAPI_MP_STRING(field, "correction field file (.tcf)");
static char* mode = nullptr;
RTAPI_MP_STRING(mode, "tcp or joint");
static char* tools = nullptr;
RTAPI_MP_STRING(tools, "tools the field must have a layer for, comma-separated");
static char* names = nullptr;
RTAPI_MP_STRING(names, "instance names, comma-separated");
static int count = -1;  // -1: not given
RTAPI_MP_INT(count, "number of instances");

struct tc_hal {
  int comp_id = -1;
  std::string error;
  struct PinSlot {
    void** shm_slot;   // the pointer LinuxCNC updates
    void** comp_slot;  // the component's own pointer
  };
  std::vector<PinSlot> pins;
  struct Funct {
    tc_hal_t* hal;
    tc_hal_funct_t fn;
    void* arg;
  };
  std::vector<Funct*> functs;  // owned; LinuxCNC holds their addresses
  struct Service {
    tc_hal_service_t fn;
    void* arg;
  };
  std::vector<Service> services;
  void* module_state = nullptr;
  std::atomic<bool> cycles_ran{false};  // a LinuxCNC thread has called a funct

  std::thread service_thread;
  std::mutex mutex;
  std::condition_variable wake;
  bool stopping = false;
};

namespace {

constexpr auto kServicePeriod = std::chrono::milliseconds(10);

tc_hal g_hal;

int api_component_new(tc_hal_t* hal, const char*) {
  // Every instance's pins belong to the one LinuxCNC component named after
  // the module (halcmd's loadrt looks for it), as in halcompile's modules.
  return hal->comp_id;
}

int api_component_ready(tc_hal_t*, int) {
  return 0;  // hal_ready() once init has succeeded
}

void* api_alloc(tc_hal_t*, size_t size) {
  void* p = hal_malloc(static_cast<long>(size));
  if (p != nullptr) std::memset(p, 0, size);
  return p;
}

int api_pin_new(tc_hal_t* hal, int comp_id, const char* name, tc_hal_type_t type,
                tc_hal_pin_dir_t dir, void** data_ptr_addr) {
  if (data_ptr_addr == nullptr) return -EINVAL;
  try {
    hal->pins.reserve(hal->pins.size() + 1);
  } catch (...) {
    return -ENOMEM;
  }
  auto* slot = static_cast<void**>(api_alloc(hal, sizeof(void*)));
  if (slot == nullptr) return -ENOMEM;
  const int r = hal_pin_new(name, static_cast<hal_type_t>(type), static_cast<hal_pin_dir_t>(dir),
                            slot, comp_id);
  if (r != 0) return r;
  *data_ptr_addr = *slot;
  hal->pins.push_back({slot, data_ptr_addr});
  return 0;
}

int api_param_new(tc_hal_t*, int comp_id, const char* name, tc_hal_type_t type,
                  tc_hal_param_dir_t dir, void* data_addr) {
  // LinuxCNC requires data_addr in HAL shared memory: components allocate it
  // with api->alloc (as the ABI asks).
  return hal_param_new(name, static_cast<hal_type_t>(type), static_cast<hal_param_dir_t>(dir),
                       data_addr, comp_id);
}

void run_funct(void* arg, long period_ns) {
  auto& f = *static_cast<tc_hal::Funct*>(arg);
  for (const tc_hal::PinSlot& p : f.hal->pins)
    *p.comp_slot = *p.shm_slot;
  f.fn(f.arg, period_ns);
  f.hal->cycles_ran.store(true, std::memory_order_relaxed);
}

int api_funct_new(tc_hal_t* hal, int comp_id, const char* name, tc_hal_funct_t funct, void* arg,
                  int uses_fp) {
  if (funct == nullptr) return -EINVAL;
  tc_hal::Funct* f = nullptr;
  try {
    hal->functs.reserve(hal->functs.size() + 1);
    f = new tc_hal::Funct{hal, funct, arg};
  } catch (...) {
    return -ENOMEM;
  }
  const int r = hal_export_funct(name, run_funct, f, uses_fp, 0, comp_id);
  if (r != 0) {
    delete f;
    return r;
  }
  hal->functs.push_back(f);
  return 0;
}

int api_service_new(tc_hal_t* hal, int, tc_hal_service_t service, void* arg) {
  if (service == nullptr) return -EINVAL;
  try {
    hal->services.push_back({service, arg});
  } catch (...) {
    return -ENOMEM;
  }
  return 0;
}

// LinuxCNC plans motion in its own real-time module, not in this one's
// service thread: background services share that thread with the others.
int api_background_service_new(tc_hal_t* hal, int comp_id, tc_hal_service_t service, void* arg) {
  return api_service_new(hal, comp_id, service, arg);
}

void api_request_stop(tc_hal_t*) {
  // LinuxCNC's threads run until `stop` or unload: nothing to ask for.
}

msg_level_t level_of(tc_hal_msg_level_t level) {
  switch (level) {
    case TC_HAL_MSG_ERR:
      return RTAPI_MSG_ERR;
    case TC_HAL_MSG_WARN:
      return RTAPI_MSG_WARN;
    default:
      return RTAPI_MSG_INFO;
  }
}

void api_message(tc_hal_t*, tc_hal_msg_level_t level, const char* text) {
  rtapi_print_msg(level_of(level), "%s\n", text != nullptr ? text : "");
}

void api_set_error(tc_hal_t* hal, const char* text) {
  try {
    hal->error = text != nullptr ? text : "";
  } catch (...) {
  }
}

const char* api_output_dir(tc_hal_t*) {
  return ".";  // rtapi_app's working folder
}

// rtapi_app handles SIGINT and SIGTERM itself (it unloads the modules):
// a component's temporary file is not this adapter's to remove.
int api_pending_file_add(tc_hal_t*, const char*) {
  return -ENOTSUP;
}

void api_pending_file_done(tc_hal_t*, int) {}

int api_cycles_ran(tc_hal_t* hal) {
  return hal->cycles_ran.load(std::memory_order_relaxed) ? 1 : 0;
}

const tc_hal_api_t kApi = {
    TC_HAL_ABI_VERSION,
    sizeof(tc_hal_api_t),
    api_component_new,
    api_component_ready,
    api_alloc,
    api_pin_new,
    api_param_new,
    api_funct_new,
    api_service_new,
    api_request_stop,
    api_message,
    api_set_error,
    api_output_dir,
    api_background_service_new,
    api_pending_file_add,
    api_pending_file_done,
    api_cycles_ran,
};

void run_services(tc_hal_t* hal) {
  for (const tc_hal::Service& s : hal->services) {
    try {
      s.fn(s.arg);
    } catch (...) {
    }
  }
}

void service_loop(tc_hal_t* hal) {
  std::unique_lock<std::mutex> lock(hal->mutex);
  while (!hal->stopping) {
    lock.unlock();
    run_services(hal);
    lock.lock();
    hal->wake.wait_for(lock, kServicePeriod, [hal] { return hal->stopping; });
  }
}

void free_functs(tc_hal_t* hal) {
  for (tc_hal::Funct* f : hal->functs)
    delete f;
  hal->functs.clear();
}

}  // namespace

extern "C" int rtapi_app_main(void) {
  tc_hal_t* hal = &g_hal;
  hal->comp_id = hal_init(TRUECUT_LINUXCNC_MODULE);
  if (hal->comp_id < 0) {
    rtapi_print_msg(RTAPI_MSG_ERR, "%s: hal_init() failed\n", TRUECUT_LINUXCNC_MODULE);
    return hal->comp_id;
  }
  int r = 0;
  try {
    std::vector<std::string> args;
    auto add = [&](const char* key, const char* value) {
      if (value != nullptr) args.push_back(std::string(key) + "=" + value);
    };
    add("field", field);
    add("mode", mode);
    add("tools", tools);
    add("names", names);
    if (count != -1) add("count", std::to_string(count).c_str());
    std::vector<const char*> argv;
    for (const std::string& a : args)
      argv.push_back(a.c_str());
    r = truecut_component_init(&kApi, hal, static_cast<int>(argv.size()), argv.data(),
                               &hal->module_state);
    if (r == 0) hal->service_thread = std::thread(service_loop, hal);
  } catch (...) {
    if (r == 0) {
      // init succeeded but the service thread could not start
      truecut_component_exit(&kApi, hal, hal->module_state);
      hal->error = "cannot start the service thread";
    }
    r = -ENOMEM;
  }
  if (r != 0) {
    rtapi_print_msg(RTAPI_MSG_ERR, "%s: %s\n", TRUECUT_LINUXCNC_MODULE,
                    hal->error.empty() ? "init failed" : hal->error.c_str());
    hal_exit(hal->comp_id);
    free_functs(hal);
    return r < 0 ? r : -EINVAL;
  }
  hal_ready(hal->comp_id);
  return 0;
}

extern "C" void rtapi_app_exit(void) {
  tc_hal_t* hal = &g_hal;
  {
    std::lock_guard<std::mutex> lock(hal->mutex);
    hal->stopping = true;
  }
  hal->wake.notify_all();
  if (hal->service_thread.joinable()) hal->service_thread.join();
  // Out of the threads first: no function of the component runs after this.
  hal_exit(hal->comp_id);
  run_services(hal);  // once after the threads stop, as the shim does
  truecut_component_exit(&kApi, hal, hal->module_state);
  free_functs(hal);
}
