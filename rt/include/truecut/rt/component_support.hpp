// Header-only helpers for writing HAL components in C++ against the C ABI.
// Nothing here needs linking with truecut, so shared-library components can
// use it freely. None of it is for the servo cycle: init time only.
#pragma once

#include <cstdlib>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "truecut/rt/hal_abi.h"

namespace truecut::rt::hal::component {

// Thrown by the helpers; caught by init_guard() and turned into set_error().
struct InitError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// The HAL refused a request and already holds the reason.
struct HalRefused : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The loadrt arguments `key=value`, each key used at most once.
class Args {
 public:
  Args(int argc, const char* const* argv) {
    for (int i = 0; i < argc; ++i) {
      std::string a = argv[i];
      auto eq = a.find('=');
      if (eq == std::string::npos || eq == 0)
        throw InitError("argument '" + a + "' is not key=value");
      auto [it, fresh] = values_.emplace(a.substr(0, eq), a.substr(eq + 1));
      if (!fresh) throw InitError("argument '" + it->first + "' given twice");
    }
  }
  std::optional<std::string> take(const std::string& key) {
    auto it = values_.find(key);
    if (it == values_.end()) return std::nullopt;
    std::string v = it->second;
    values_.erase(it);
    return v;
  }
  std::string take_or(const std::string& key, const std::string& fallback) {
    auto v = take(key);
    return v ? *v : fallback;
  }
  double take_double(const std::string& key, double fallback) {
    auto v = take(key);
    if (!v) return fallback;
    char* end = nullptr;
    double d = std::strtod(v->c_str(), &end);
    if (v->empty() || *end != '\0') throw InitError(key + "='" + *v + "' is not a number");
    return d;
  }
  long take_long(const std::string& key, long fallback, long min, long max) {
    auto v = take(key);
    if (!v) return fallback;
    char* end = nullptr;
    long n = std::strtol(v->c_str(), &end, 0);
    if (v->empty() || *end != '\0') throw InitError(key + "='" + *v + "' is not an integer");
    if (n < min || n > max)
      throw InitError(key + "=" + *v + " is outside " + std::to_string(min) + ".." +
                      std::to_string(max));
    return n;
  }
  // Call after taking every known key: names the first unknown one.
  void expect_consumed(const char* component) const {
    if (!values_.empty())
      throw InitError(std::string(component) + " has no argument '" + values_.begin()->first + "'");
  }

 private:
  std::map<std::string, std::string> values_;
};

// LinuxCNC's instance naming: `count=N` gives `<comp>.0` .. `<comp>.N-1`,
// `names=a,b` gives exactly those; neither gives one instance `<comp>.0`.
inline std::vector<std::string> instance_names(Args& args, const std::string& comp,
                                               int max_count = 64) {
  auto count = args.take("count");
  auto names = args.take("names");
  if (count && names) throw InitError("count= and names= cannot both be given");
  std::vector<std::string> out;
  if (names) {
    std::string cur;
    for (char c : *names + ",") {
      if (c != ',') {
        cur += c;
        continue;
      }
      if (cur.empty()) throw InitError("names='" + *names + "' has an empty name");
      out.push_back(cur);
      cur.clear();
    }
  } else {
    long n = 1;
    if (count) {
      char* end = nullptr;
      n = std::strtol(count->c_str(), &end, 10);
      if (count->empty() || *end != '\0' || n < 1 || n > max_count)
        throw InitError("count=" + *count + " must be 1.." + std::to_string(max_count));
    }
    for (long i = 0; i < n; ++i)
      out.push_back(comp + "." + std::to_string(i));
  }
  return out;
}

// Wraps a component's init body: turns InitError (and anything else) into
// set_error() plus a negative errno, so no exception crosses the C ABI.
template <class F>
int init_guard(const tc_hal_api_t* api, tc_hal_t* hal, F&& body) {
  try {
    return body();
  } catch (const HalRefused&) {
    return -22;  // EINVAL; the HAL keeps its own reason
  } catch (const std::exception& e) {
    api->set_error(hal, e.what());
    return -22;  // EINVAL
  } catch (...) {
    api->set_error(hal, "unknown error");
    return -22;
  }
}

// Thin wrappers that throw InitError with the HAL's reason.
class Builder {
 public:
  Builder(const tc_hal_api_t* api, tc_hal_t* hal, int comp_id)
      : api_(api), hal_(hal), comp_(comp_id) {}
  template <class T>
  void pin(const std::string& name, tc_hal_type_t type, tc_hal_pin_dir_t dir, T** ptr) {
    if (api_->pin_new(hal_, comp_, name.c_str(), type, dir, reinterpret_cast<void**>(ptr)) != 0)
      throw HalRefused(name);
  }
  template <class T>
  void param(const std::string& name, tc_hal_type_t type, tc_hal_param_dir_t dir, T* data) {
    if (api_->param_new(hal_, comp_, name.c_str(), type, dir, data) != 0) throw HalRefused(name);
  }
  void funct(const std::string& name, tc_hal_funct_t fn, void* arg) {
    if (api_->funct_new(hal_, comp_, name.c_str(), fn, arg, 1) != 0) throw HalRefused(name);
  }
  void service(tc_hal_service_t fn, void* arg) {
    if (api_->service_new(hal_, comp_, fn, arg) != 0) throw HalRefused("service");
  }
  // Work that may take long (reading a file): its own thread on the wall
  // clock (hal_abi.h). A host whose table predates it runs it as a service.
  void background_service(tc_hal_service_t fn, void* arg) {
    const int r = TC_HAL_API_HAS(api_, background_service_new)
                      ? api_->background_service_new(hal_, comp_, fn, arg)
                      : api_->service_new(hal_, comp_, fn, arg);
    if (r != 0) throw HalRefused("background service");
  }
  template <class T>
  T* alloc() {
    void* p = api_->alloc(hal_, sizeof(T));
    if (!p) throw InitError("out of memory");
    return new (p) T();
  }

 private:
  const tc_hal_api_t* api_;
  tc_hal_t* hal_;
  int comp_;
};

inline int new_component(const tc_hal_api_t* api, tc_hal_t* hal, const std::string& name) {
  int id = api->component_new(hal, name.c_str());
  if (id <= 0) throw HalRefused(name);
  return id;
}

}  // namespace truecut::rt::hal::component
