#include "json_node.hpp"

#include <cmath>
#include <set>

#include "truecut/rt/number_format.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::sim::detail {

std::string format_number(double v) {
  return rt::format_printf("%g", v);
}

void JsonNode::fail(const std::string& message) const {
  throw MachineDescriptionError(*file_ + ": " + (path_.empty() ? "(top level)" : path_) + ": " +
                                message);
}

void JsonNode::expect_object() const {
  if (!value_->is_object()) fail("must be an object");
}

void JsonNode::allow_only(const std::vector<std::string>& known, std::string_view what) const {
  expect_object();
  for (const auto& item : value_->items()) {
    bool ok = false;
    for (const auto& k : known)
      ok = ok || k == item.key();
    if (ok) continue;
    std::string list;
    for (const auto& k : known)
      list += (list.empty() ? "" : ", ") + k;
    JsonNode(*file_, item.value(), path_.empty() ? item.key() : path_ + "." + item.key())
        .fail("unknown " + std::string(what) + "; known: " + list);
  }
}

bool JsonNode::has(const std::string& key) const {
  return value_->is_object() && value_->contains(key);
}

JsonNode JsonNode::child(const std::string& key) const {
  expect_object();
  const std::string p = path_.empty() ? key : path_ + "." + key;
  auto it = value_->find(key);
  if (it == value_->end()) {
    static const nlohmann::json null_value;
    JsonNode(*file_, null_value, p).fail("missing");
  }
  return JsonNode(*file_, *it, p);
}

double JsonNode::number() const {
  if (!value_->is_number()) fail("must be a number");
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("must be finite");
  return v;
}

std::array<double, 3> JsonNode::vector3() const {
  if (!value_->is_array() || value_->size() != 3) fail("must be an array of 3 numbers [x, y, z]");
  std::array<double, 3> v;
  for (size_t i = 0; i < 3; ++i)
    v[i] = JsonNode(*file_, (*value_)[i], path_ + "[" + std::to_string(i) + "]").number();
  return v;
}

bool JsonNode::boolean() const {
  if (!value_->is_boolean()) fail("must be true or false");
  return value_->get<bool>();
}

std::string JsonNode::string() const {
  if (!value_->is_string()) fail("must be a string");
  return value_->get<std::string>();
}

long JsonNode::integer() const {
  if (!value_->is_number_integer()) fail("must be an integer");
  return value_->get<long>();
}

nlohmann::json parse_json_strict(const std::string& text, const std::string& file) {
  // Duplicate keys are silently merged by JSON parsers; here they are errors.
  struct Frame {
    std::set<std::string> keys;
    std::string key;
  };
  std::vector<Frame> stack;
  std::string duplicate;
  auto path = [&](const std::string& last) {
    std::string p;
    for (size_t i = 0; i + 1 < stack.size(); ++i)
      p += stack[i].key + ".";
    return p + last;
  };
  auto callback = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (event == E::object_start || event == E::array_start)
      stack.push_back({});
    else if (event == E::object_end || event == E::array_end) {
      if (!stack.empty()) stack.pop_back();
    } else if (event == E::key && !stack.empty()) {
      const std::string k = parsed.get<std::string>();
      if (!stack.back().keys.insert(k).second && duplicate.empty()) duplicate = path(k);
      stack.back().key = k;
    }
    return true;
  };
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text, callback);
  } catch (const nlohmann::json::exception& e) {  // parse errors, number overflow
    std::string what = e.what();
    if (auto pos = what.find("] "); pos != std::string::npos) what = what.substr(pos + 2);
    throw MachineDescriptionError(file + ": not valid JSON: " + what);
  }
  if (!duplicate.empty())
    throw MachineDescriptionError(file + ": " + duplicate + ": key given twice");
  return root;
}

}  // namespace truecut::sim::detail
