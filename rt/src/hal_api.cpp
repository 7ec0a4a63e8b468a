// The C function table handed to components. Every entry catches what the
// C++ side throws: nothing may unwind through a component's C frames.
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "hal_state.hpp"

using namespace truecut::rt::hal;
using namespace truecut::rt::hal::detail;

namespace {

bool valid_type(int t) {
  return t >= TC_HAL_BIT && t <= TC_HAL_U32;
}
bool valid_pin_dir(int d) {
  return d == TC_HAL_IN || d == TC_HAL_OUT || d == TC_HAL_IO;
}

template <class F>
int guarded(tc_hal* hal, F&& f) {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    hal->load_error = "out of memory";
    return -ENOMEM;
  } catch (const std::exception& e) {
    hal->load_error = e.what();
    return -EINVAL;
  }
}

int api_component_new(tc_hal* hal, const char* name) {
  return guarded(hal, [&] {
    if (!name || !*name) throw HalError("component name is empty");
    if (hal->loading_module.empty())
      throw HalError("component_new('" + std::string(name) + "') called outside loadrt");
    for (const auto& c : hal->components)
      if (c->name == name) throw HalError("component '" + std::string(name) + "' already exists");
    auto comp = std::make_unique<Component>();
    comp->id = hal->next_comp_id++;
    comp->name = name;
    comp->module = hal->loading_module;
    int id = comp->id;
    hal->components.push_back(std::move(comp));
    return id;
  });
}

int api_component_ready(tc_hal* hal, int comp_id) {
  return guarded(hal, [&] {
    Component* c = hal->component(comp_id);
    if (!c) throw HalError("component_ready: no component " + std::to_string(comp_id));
    c->ready = true;
    return 0;
  });
}

void* api_alloc(tc_hal* hal, size_t size_bytes) {
  try {
    auto block = std::make_unique<unsigned char[]>(size_bytes == 0 ? 1 : size_bytes);
    std::memset(block.get(), 0, size_bytes == 0 ? 1 : size_bytes);
    void* p = block.get();
    hal->allocations.push_back(std::move(block));
    return p;
  } catch (...) {
    return nullptr;
  }
}

int api_pin_new(tc_hal* hal, int comp_id, const char* name, tc_hal_type_t type,
                tc_hal_pin_dir_t dir, void** data_ptr_addr) {
  return guarded(hal, [&] {
    std::string n = name ? name : "";
    if (!valid_type(type)) throw HalError("pin '" + n + "': invalid type " + std::to_string(type));
    if (!valid_pin_dir(dir))
      throw HalError("pin '" + n + "': invalid direction " + std::to_string(dir));
    hal->add_pin(comp_id, n, static_cast<Type>(type), static_cast<PinDir>(dir), data_ptr_addr);
    return 0;
  });
}

int api_param_new(tc_hal* hal, int comp_id, const char* name, tc_hal_type_t type,
                  tc_hal_param_dir_t dir, void* data_addr) {
  return guarded(hal, [&] {
    std::string n = name ? name : "";
    if (!valid_type(type))
      throw HalError("parameter '" + n + "': invalid type " + std::to_string(type));
    if (dir != TC_HAL_RO && dir != TC_HAL_RW)
      throw HalError("parameter '" + n + "': invalid direction " + std::to_string(dir));
    hal->add_param(comp_id, n, static_cast<Type>(type), static_cast<ParamDir>(dir), data_addr);
    return 0;
  });
}

int api_funct_new(tc_hal* hal, int comp_id, const char* name, tc_hal_funct_t fn, void* arg,
                  int uses_fp) {
  return guarded(hal, [&] {
    std::string n = name ? name : "";
    if (n.empty()) throw HalError("function name is empty");
    if (!fn) throw HalError("function '" + n + "': NULL function pointer");
    if (!hal->component(comp_id)) throw HalError("function '" + n + "': no such component");
    if (hal->functs.count(n)) throw HalError("function '" + n + "' already exists");
    auto f = std::make_unique<Funct>();
    f->name = n;
    f->comp_id = comp_id;
    f->fn = fn;
    f->arg = arg;
    f->uses_fp = uses_fp != 0;
    Funct* raw = f.get();
    hal->functs.emplace(n, std::move(f));
    try {
      hal->add_pin(comp_id, n + ".time", Type::kS32, PinDir::kOut, &raw->time_pin);
      hal->add_param(comp_id, n + ".tmax", Type::kS32, ParamDir::kRw, &raw->tmax_ns);
      hal->add_param(comp_id, n + ".tmax-increased", Type::kBit, ParamDir::kRo,
                     &raw->tmax_increased);
    } catch (...) {
      hal->pins.erase(n + ".time");
      hal->params.erase(n + ".tmax");
      hal->functs.erase(n);
      throw;
    }
    return 0;
  });
}

int add_service(tc_hal* hal, int comp_id, tc_hal_service_t fn, void* arg, bool background) {
  return guarded(hal, [&] {
    if (!fn) throw HalError("service: NULL function pointer");
    if (!hal->component(comp_id)) throw HalError("service: no such component");
    hal->services.push_back({comp_id, fn, arg, background});
    return 0;
  });
}

int api_service_new(tc_hal* hal, int comp_id, tc_hal_service_t fn, void* arg) {
  return add_service(hal, comp_id, fn, arg, false);
}

int api_background_service_new(tc_hal* hal, int comp_id, tc_hal_service_t fn, void* arg) {
  return add_service(hal, comp_id, fn, arg, true);
}

void api_request_stop(tc_hal* hal) {
  hal->stop.store(true, std::memory_order_relaxed);
}

void api_message(tc_hal* hal, tc_hal_msg_level_t level, const char* text) {
  if (level == TC_HAL_MSG_ERR) ++hal->error_messages;
  if (level != TC_HAL_MSG_ERR && level != TC_HAL_MSG_WARN && !hal->options.show_info_messages)
    return;
  const char* tag = level == TC_HAL_MSG_ERR    ? "error"
                    : level == TC_HAL_MSG_WARN ? "warning"
                                               : "info";
  const std::string line = (hal->loading_module.empty() ? "hal" : hal->loading_module) + ": " +
                           tag + ": " + (text ? text : "") + "\n";
  if (hal->options.message_sink)
    hal->options.message_sink(line);
  else
    std::fputs(line.c_str(), stderr);
}

void api_set_error(tc_hal* hal, const char* text) {
  hal->load_error = text ? text : "";
}

const char* api_output_dir(tc_hal* hal) {
  return hal->output_dir_text.c_str();
}

int api_pending_file_add(tc_hal* hal, const char* path) {
  if (path == nullptr || *path == '\0') return -EINVAL;
  try {
    auto file = std::make_unique<truecut::rt::PendingFile>(path);
    if (!file->tracked()) return -ENOSPC;  // table full, or a path beyond its bytes
    const std::lock_guard<std::mutex> lock(hal->pending_files_mutex);
    const int handle = hal->next_pending_file++;
    hal->pending_files.emplace(handle, std::move(file));
    return handle;
  } catch (...) {
    return -ENOMEM;
  }
}

void api_pending_file_done(tc_hal* hal, int handle) {
  std::unique_ptr<truecut::rt::PendingFile> done;  // released outside the lock
  const std::lock_guard<std::mutex> lock(hal->pending_files_mutex);
  auto it = hal->pending_files.find(handle);
  if (it == hal->pending_files.end()) return;
  done = std::move(it->second);
  hal->pending_files.erase(it);
}

int api_cycles_ran(tc_hal* hal) {
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

}  // namespace

const tc_hal_api_t* truecut::rt::hal::Hal::api() {
  return &kApi;
}
