#include "truecut/rt/hal.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cstring>

#include "hal_state.hpp"

using truecut::rt::hal::HalError;
using namespace truecut::rt::hal::detail;

namespace truecut::rt::hal {
namespace {

Value read_data(Type type, const void* data) {
  switch (type) {
    case Type::kBit:
      return Value::of_bit(*static_cast<const bool*>(data));
    case Type::kFloat:
      return Value::of_float(*static_cast<const double*>(data));
    case Type::kS32:
      return Value::of_s32(*static_cast<const int32_t*>(data));
    case Type::kU32:
      return Value::of_u32(*static_cast<const uint32_t*>(data));
  }
  return {};
}

void write_data(const Value& v, void* data) {
  switch (v.type) {
    case Type::kBit:
      *static_cast<bool*>(data) = v.b;
      break;
    case Type::kFloat:
      *static_cast<double*>(data) = v.f;
      break;
    case Type::kS32:
      *static_cast<int32_t*>(data) = v.s;
      break;
    case Type::kU32:
      *static_cast<uint32_t*>(data) = v.u;
      break;
  }
}

std::string q(const std::string& s) {
  return "'" + s + "'";
}

void remove_component(tc_hal& st, int comp_id) {
  for (auto it = st.pins.begin(); it != st.pins.end();) {
    Pin& pin = *it->second;
    if (pin.comp_id != comp_id) {
      ++it;
      continue;
    }
    if (pin.signal) {
      Signal& sig = *pin.signal;
      (pin.dir == PinDir::kOut ? sig.writers : pin.dir == PinDir::kIo ? sig.bidirs : sig.readers)--;
    }
    it = st.pins.erase(it);
  }
  std::erase_if(st.params, [&](const auto& kv) { return kv.second->comp_id == comp_id; });
  for (auto it = st.functs.begin(); it != st.functs.end();) {
    if (it->second->comp_id != comp_id) {
      ++it;
      continue;
    }
    for (auto& th : st.threads)
      std::erase(th->functs, it->second.get());
    it = st.functs.erase(it);
  }
  std::erase_if(st.services, [&](const Service& s) { return s.comp_id == comp_id; });
  std::erase_if(st.components, [&](const auto& c) { return c->id == comp_id; });
}

std::vector<std::filesystem::path> candidate_files(const HalOptions& opt,
                                                   const std::string& module) {
  std::vector<std::filesystem::path> out;
  for (const auto& dir : opt.component_path)
    out.push_back(dir / (module + ".so"));
  return out;
}

// Calls a module's init; on failure undoes everything it created.
void run_init(tc_hal& st, Module& mod, tc_component_init_fn init,
              const std::vector<std::string>& args) {
  const std::string module = mod.name;
  std::vector<const char*> argv;
  for (const auto& a : args)
    argv.push_back(a.c_str());
  argv.push_back(nullptr);
  st.loading_module = module;
  st.load_error.clear();
  int rc = init(Hal::api(), &st, static_cast<int>(args.size()), argv.data(), &mod.state);
  st.loading_module.clear();

  std::string not_ready;
  for (const auto& c : st.components)
    if (c->module == module && !c->ready) not_ready += " " + c->name;
  if (rc == 0 && not_ready.empty()) {
    st.modules.push_back(std::move(mod));
    return;
  }
  // Undo a failed load completely, as LinuxCNC's hal_exit would.
  std::vector<int> ids;
  for (const auto& c : st.components)
    if (c->module == module) ids.push_back(c->id);
  if (rc == 0 && mod.exit) mod.exit(Hal::api(), &st, mod.state);
  for (int id : ids)
    remove_component(st, id);
  if (mod.dl_handle) dlclose(mod.dl_handle);
  if (rc != 0)
    throw HalError("loadrt " + module + ": initialisation failed (" + std::strerror(-rc) + ")" +
                   (st.load_error.empty() ? "" : ": " + st.load_error));
  throw HalError("loadrt " + module + ": component(s)" + not_ready + " never became ready");
}

}  // namespace

Hal::Hal(HalOptions options) : state_(std::make_unique<tc_hal>()) {
  state_->options = std::move(options);
  state_->output_dir_text = state_->options.output_dir.string();
}

int Hal::unload() {
  auto& st = *state_;
  if (st.unloaded) return 0;
  st.unloaded = true;
  const int before = st.error_messages;
  for (auto it = st.modules.rbegin(); it != st.modules.rend(); ++it) {
    if (it->exit) it->exit(api(), state_.get(), it->state);
  }
  return st.error_messages - before;
}

Hal::~Hal() {
  auto& st = *state_;
  unload();
  // Nothing may point into a library once it is closed.
  st.services.clear();
  st.functs.clear();
  st.threads.clear();
  for (auto it = st.modules.rbegin(); it != st.modules.rend(); ++it) {
    if (it->dl_handle) dlclose(it->dl_handle);
  }
}

const HalOptions& Hal::options() const {
  return state_->options;
}

bool Hal::is_loaded(const std::string& module) const {
  return std::any_of(state_->modules.begin(), state_->modules.end(),
                     [&](const Module& m) { return m.name == module; });
}

void Hal::load(const std::string& module, const std::vector<std::string>& args) {
  auto& st = *state_;
  if (module == "threads") {
    // LinuxCNC's `loadrt threads name1=... period1=... fp1=...`, once per HAL
    // like any module (more threads: name2=..., or newthread).
    if (st.threads_loaded) throw HalError("module 'threads' is already loaded");
    for (int i = 1; i <= 9; ++i) {
      std::string name, period;
      bool fp = true;
      for (const auto& a : args) {
        auto eq = a.find('=');
        if (eq == std::string::npos)
          throw HalError("threads: argument '" + a + "' is not key=value");
        std::string k = a.substr(0, eq), v = a.substr(eq + 1);
        if (k == "name" + std::to_string(i)) name = v;
        if (k == "period" + std::to_string(i)) period = v;
        if (k == "fp" + std::to_string(i)) fp = parse_value(Type::kBit, v).b;
      }
      if (name.empty() && period.empty()) continue;
      if (name.empty() || period.empty())
        throw HalError("threads: thread " + std::to_string(i) + " needs both name" +
                       std::to_string(i) + "= and period" + std::to_string(i) + "=");
      new_thread(name, parse_value(Type::kS32, period).s, fp);
    }
    st.threads_loaded = true;
    return;
  }
  if (is_loaded(module)) throw HalError("module " + q(module) + " is already loaded");

  Module mod;
  mod.name = module;
  tc_component_init_fn init = nullptr;
  for (const auto& b : builtin_components()) {
    if (module == b.name) {
      init = b.init;
      mod.exit = b.exit;
    }
  }
  if (!init) {
    std::string searched;
    for (const auto& file : candidate_files(st.options, module)) {
      if (!std::filesystem::exists(file)) {
        searched += "\n  " + file.string();
        continue;
      }
      void* h = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!h) throw HalError("cannot load " + file.string() + ": " + dlerror());
      init = reinterpret_cast<tc_component_init_fn>(dlsym(h, TC_COMPONENT_INIT_SYMBOL));
      mod.exit = reinterpret_cast<tc_component_exit_fn>(dlsym(h, TC_COMPONENT_EXIT_SYMBOL));
      if (!init || !mod.exit) {
        dlclose(h);
        throw HalError(file.string() + " is not a truecut component: it does not export " +
                       TC_COMPONENT_INIT_SYMBOL + " and " + TC_COMPONENT_EXIT_SYMBOL);
      }
      mod.dl_handle = h;
      break;
    }
    if (!init)
      throw HalError("no component " + q(module) + ": not built in, and no " + module +
                     ".so in the component path" +
                     (searched.empty() ? std::string(" (the path is empty)") : ":" + searched));
  }

  run_init(st, mod, init, args);
}

void Hal::load(const std::string& module, tc_component_init_fn init, tc_component_exit_fn exit,
               const std::vector<std::string>& args) {
  if (is_loaded(module)) throw HalError("module " + q(module) + " is already loaded");
  if (!init) throw HalError("module " + q(module) + ": no init function");
  Module mod;
  mod.name = module;
  mod.exit = exit;
  run_init(*state_, mod, init, args);
}

void Hal::new_thread(const std::string& name, int64_t period_ns, bool uses_fp) {
  auto& st = *state_;
  if (name.empty()) throw HalError("thread name is empty");
  if (st.thread(name)) throw HalError("thread " + q(name) + " already exists");
  if (period_ns <= 0) throw HalError("thread " + q(name) + ": period must be > 0 ns");
  if (period_ns < 10000)
    throw HalError("thread " + q(name) + ": period " + std::to_string(period_ns) +
                   " ns is below the 10000 ns minimum");
  if (st.threads.size() >= kMaxThreads)
    throw HalError("thread " + q(name) + ": more than " + std::to_string(kMaxThreads) +
                   " threads (LinuxCNC's RTAPI has as many tasks at most)");
  // Thread pins belong to a HAL-owned component named after the thread.
  auto comp = std::make_unique<Component>();
  comp->id = st.next_comp_id++;
  comp->name = name;
  comp->module = "threads";
  comp->ready = true;
  int comp_id = comp->id;
  st.components.push_back(std::move(comp));

  auto th = std::make_unique<Thread>();
  th->name = name;
  th->period_ns = period_ns;
  th->uses_fp = uses_fp;
  st.add_pin(comp_id, name + ".time", Type::kS32, PinDir::kOut, &th->time_pin);
  st.add_pin(comp_id, name + ".overruns", Type::kU32, PinDir::kOut, &th->overruns_pin);
  st.add_pin(comp_id, name + ".cycles", Type::kU32, PinDir::kOut, &th->cycles_pin);
  st.add_param(comp_id, name + ".tmax", Type::kS32, ParamDir::kRw, &th->tmax_ns);
  st.threads.push_back(std::move(th));
}

void Hal::add_function(const std::string& funct, const std::string& thread, int position) {
  auto& st = *state_;
  auto fit = st.functs.find(funct);
  if (fit == st.functs.end()) throw HalError("function " + q(funct) + " not found");
  Thread* th = st.thread(thread);
  if (!th) throw HalError("thread " + q(thread) + " not found");
  Funct& f = *fit->second;
  if (!f.thread.empty())
    throw HalError("function " + q(funct) + " already added to thread " + q(f.thread));
  if (f.uses_fp && !th->uses_fp)
    throw HalError("function " + q(funct) + " needs floating point but thread " + q(thread) +
                   " is nofp");
  const int n = static_cast<int>(th->functs.size());
  if (position == 0) throw HalError("addf position 0 is not valid (1 = first, -1 = last)");
  if (position > n + 1 || position < -(n + 1))
    throw HalError("addf position " + std::to_string(position) + " is beyond the " +
                   std::to_string(n) + " function(s) of thread " + q(thread));
  int index = position > 0 ? position - 1 : n + 1 + position;
  th->functs.insert(th->functs.begin() + index, &f);
  f.thread = thread;
}

void Hal::new_signal(const std::string& name, Type type) {
  auto& st = *state_;
  if (name.empty()) throw HalError("signal name is empty");
  if (st.signals.count(name)) throw HalError("signal " + q(name) + " already exists");
  if (st.pins.count(name) || st.params.count(name))
    throw HalError("signal name " + q(name) + " is already the name of a pin or parameter");
  auto sig = std::make_unique<Signal>();
  sig->name = name;
  sig->type = type;
  st.signals.emplace(name, std::move(sig));
}

void Hal::link(const std::string& pin_name, const std::string& signal_name) {
  auto& st = *state_;
  auto pit = st.pins.find(pin_name);
  if (pit == st.pins.end()) {
    if (st.signals.count(pin_name))
      throw HalError(q(pin_name) + " is a signal, not a pin (one signal per net)");
    throw HalError("pin " + q(pin_name) + " does not exist");
  }
  Pin& pin = *pit->second;
  if (!st.signals.count(signal_name)) new_signal(signal_name, pin.type);
  Signal& sig = *st.signals.at(signal_name);
  if (pin.signal == &sig) return;
  if (pin.signal)
    throw HalError("pin " + q(pin_name) + " is already linked to signal " + q(pin.signal->name));
  if (pin.type != sig.type)
    throw HalError("type mismatch: pin " + q(pin_name) + " is " + to_string(pin.type) +
                   ", signal " + q(signal_name) + " is " + to_string(sig.type));
  if (pin.dir == PinDir::kOut && (sig.writers > 0 || sig.bidirs > 0)) {
    std::string other;
    for (const auto& [n, p] : st.pins)
      if (p->signal == &sig && p->dir != PinDir::kIn) other = n;
    throw HalError("signal " + q(signal_name) + " already has a writer (" + other + "); pin " +
                   q(pin_name) + " cannot be a second one");
  }
  if (pin.dir == PinDir::kIo && sig.writers > 0)
    throw HalError("signal " + q(signal_name) + " has an output pin; I/O pin " + q(pin_name) +
                   " cannot join it");
  // The first pin on a signal gives it its value, as in LinuxCNC.
  if (sig.writers + sig.bidirs + sig.readers == 0) sig.data = pin.dummy;
  (pin.dir == PinDir::kOut ? sig.writers : pin.dir == PinDir::kIo ? sig.bidirs : sig.readers)++;
  pin.signal = &sig;
  *pin.data_ptr_addr = &sig.data;
}

void Hal::unlink(const std::string& pin_name) {
  auto& st = *state_;
  auto pit = st.pins.find(pin_name);
  if (pit == st.pins.end()) throw HalError("pin " + q(pin_name) + " does not exist");
  Pin& pin = *pit->second;
  if (!pin.signal) return;
  Signal& sig = *pin.signal;
  (pin.dir == PinDir::kOut ? sig.writers : pin.dir == PinDir::kIo ? sig.bidirs : sig.readers)--;
  pin.dummy = sig.data;  // the pin keeps the value it last saw
  pin.signal = nullptr;
  *pin.data_ptr_addr = &pin.dummy;
}

void Hal::set_pin_or_param(const std::string& name, const std::string& value_text) {
  auto& st = *state_;
  if (auto it = st.params.find(name); it != st.params.end()) {
    Param& p = *it->second;
    if (p.dir == ParamDir::kRo) throw HalError("parameter " + q(name) + " is read-only");
    write_data(parse_value(p.type, value_text), p.data);
    return;
  }
  auto it = st.pins.find(name);
  if (it == st.pins.end()) throw HalError("no pin or parameter named " + q(name));
  Pin& pin = *it->second;
  if (pin.dir == PinDir::kOut)
    throw HalError("pin " + q(name) + " is an output and cannot be set with setp");
  if (pin.signal)
    throw HalError("pin " + q(name) + " is linked to signal " + q(pin.signal->name) +
                   "; use sets on the signal instead");
  write_data(parse_value(pin.type, value_text), &pin.dummy);
}

void Hal::set_signal(const std::string& name, const std::string& value_text) {
  auto& st = *state_;
  auto it = st.signals.find(name);
  if (it == st.signals.end()) throw HalError("signal " + q(name) + " does not exist");
  Signal& sig = *it->second;
  if (sig.writers > 0)
    throw HalError("signal " + q(name) + " has a writer pin; sets would be overwritten");
  write_data(parse_value(sig.type, value_text), &sig.data);
}

Value Hal::get_pin_or_param(const std::string& name) const {
  const auto& st = *state_;
  if (auto it = st.params.find(name); it != st.params.end())
    return read_data(it->second->type, it->second->data);
  auto it = st.pins.find(name);
  if (it == st.pins.end()) throw HalError("no pin or parameter named " + q(name));
  return read_data(it->second->type, *it->second->data_ptr_addr);
}

Value Hal::get_signal(const std::string& name) const {
  auto it = state_->signals.find(name);
  if (it == state_->signals.end()) throw HalError("signal " + q(name) + " does not exist");
  return read_data(it->second->type, &it->second->data);
}

bool Hal::has_pin(const std::string& n) const {
  return state_->pins.count(n) > 0;
}
bool Hal::has_param(const std::string& n) const {
  return state_->params.count(n) > 0;
}
bool Hal::has_signal(const std::string& n) const {
  return state_->signals.count(n) > 0;
}
bool Hal::has_function(const std::string& n) const {
  return state_->functs.count(n) > 0;
}
bool Hal::has_thread(const std::string& n) const {
  return state_->thread(n) != nullptr;
}

std::vector<PinInfo> Hal::pins() const {
  std::vector<PinInfo> out;
  for (const auto& [name, p] : state_->pins)
    out.push_back({name, p->type, p->dir, state_->component(p->comp_id)->name,
                   p->signal ? p->signal->name : ""});
  return out;
}

std::vector<ParamInfo> Hal::params() const {
  std::vector<ParamInfo> out;
  for (const auto& [name, p] : state_->params)
    out.push_back({name, p->type, p->dir, state_->component(p->comp_id)->name});
  return out;
}

std::vector<SignalInfo> Hal::signals() const {
  std::vector<SignalInfo> out;
  for (const auto& [name, s] : state_->signals)
    out.push_back({name, s->type, s->writers, s->bidirs, s->readers});
  return out;
}

std::vector<ThreadInfo> Hal::threads() const {
  std::vector<ThreadInfo> out;
  for (const auto& th : state_->threads) {
    ThreadInfo info{th->name, th->period_ns, th->uses_fp, {}};
    for (const Funct* f : th->functs)
      info.functions.push_back(f->name);
    out.push_back(std::move(info));
  }
  return out;
}

std::vector<std::string> Hal::functions() const {
  std::vector<std::string> out;
  for (const auto& [name, f] : state_->functs)
    out.push_back(name);
  return out;
}

void Hal::request_stop() noexcept {
  state_->stop.store(true, std::memory_order_relaxed);
}
bool Hal::stop_requested() const noexcept {
  return state_->stop.load(std::memory_order_relaxed);
}
void Hal::clear_stop() noexcept {
  state_->stop.store(false, std::memory_order_relaxed);
}

namespace {
bool selected(const Service& s, Hal::Services which) {
  return which == Hal::Services::kAll || s.background == (which == Hal::Services::kBackground);
}
}  // namespace

void Hal::run_services(Services which) {
  for (const Service& s : state_->services)
    if (selected(s, which)) s.fn(s.arg);
}

std::size_t Hal::service_count(Services which) const {
  return static_cast<std::size_t>(
      std::count_if(state_->services.begin(), state_->services.end(),
                    [&](const Service& s) { return selected(s, which); }));
}

}  // namespace truecut::rt::hal

Component* tc_hal::component(int id) const {
  for (auto& c : components)
    if (c->id == id) return c.get();
  return nullptr;
}

Thread* tc_hal::thread(const std::string& name) const {
  for (auto& t : threads)
    if (t->name == name) return t.get();
  return nullptr;
}

void tc_hal::add_pin(int comp_id, const std::string& name, truecut::rt::hal::Type type,
                     truecut::rt::hal::PinDir dir, void** data_ptr_addr) {
  if (!component(comp_id)) throw HalError("pin '" + name + "': no component with that id");
  if (name.empty()) throw HalError("pin name is empty");
  if (!data_ptr_addr) throw HalError("pin '" + name + "': data pointer address is NULL");
  if (pins.count(name) || params.count(name) || signals.count(name))
    throw HalError("duplicate name '" + name + "' (pin, parameter or signal already exists)");
  auto pin = std::make_unique<Pin>();
  pin->name = name;
  pin->type = type;
  pin->dir = dir;
  pin->comp_id = comp_id;
  pin->data_ptr_addr = data_ptr_addr;
  *data_ptr_addr = &pin->dummy;
  pins.emplace(name, std::move(pin));
}

void tc_hal::add_param(int comp_id, const std::string& name, truecut::rt::hal::Type type,
                       truecut::rt::hal::ParamDir dir, void* data) {
  if (!component(comp_id)) throw HalError("parameter '" + name + "': no component with that id");
  if (name.empty()) throw HalError("parameter name is empty");
  if (!data) throw HalError("parameter '" + name + "': data address is NULL");
  if (pins.count(name) || params.count(name) || signals.count(name))
    throw HalError("duplicate name '" + name + "' (pin, parameter or signal already exists)");
  auto p = std::make_unique<Param>();
  p->name = name;
  p->type = type;
  p->dir = dir;
  p->comp_id = comp_id;
  p->data = data;
  params.emplace(name, std::move(p));
}
