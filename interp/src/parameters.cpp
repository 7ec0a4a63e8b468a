#include "parameters.hpp"

namespace truecut::interp {

Parameters::Parameters() : numbered_(kCount, 0.0), frames_(1) {}

bool Parameters::is_predefined(std::string_view name) const {
  return predefined && predefined(name).has_value();
}

std::optional<double> Parameters::named(std::string_view name) const {
  if (predefined)
    if (auto v = predefined(name)) return v;
  if (!name.empty() && name[0] == '_') {
    auto it = globals_.find(name);
    if (it != globals_.end()) return it->second;
    return std::nullopt;
  }
  const auto& locals = frames_.back().locals;
  auto it = locals.find(name);
  if (it != locals.end()) return it->second;
  return std::nullopt;
}

ParameterValues Parameters::values() const {
  ParameterValues v;
  v.numbered = numbered_;
  v.named.insert(globals_.begin(), globals_.end());
  v.named.insert(frames_.back().locals.begin(), frames_.back().locals.end());
  return v;
}

void Parameters::set_named(const std::string& name, double value) {
  if (!name.empty() && name[0] == '_')
    globals_[name] = value;
  else
    frames_.back().locals[name] = value;
}

void Parameters::push_call(const std::vector<double>& args) {
  Frame f;
  for (int i = 0; i < kLocalCount; ++i) {
    f.saved[i] = numbered_[i + 1];
    numbered_[i + 1] = i < static_cast<int>(args.size()) ? args[i] : 0.0;
  }
  frames_.push_back(std::move(f));
}

void Parameters::push_shared_call() {
  Frame f;
  f.restores_numbered = false;
  frames_.push_back(std::move(f));
}

void Parameters::pop_call() {
  if (frames_.size() <= 1) return;
  if (frames_.back().restores_numbered)
    for (int i = 0; i < kLocalCount; ++i)
      numbered_[i + 1] = frames_.back().saved[i];
  frames_.pop_back();
}

}  // namespace truecut::interp
