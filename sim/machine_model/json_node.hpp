// A JSON value with its key path, for readers that report errors as
// "FILE: key.path: message". Internal to sim/ (keeps nlohmann out of the
// public headers).
#pragma once

#include <array>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace truecut::sim::detail {

class JsonNode {
 public:
  JsonNode(const std::string& file, const nlohmann::json& value, std::string path)
      : file_(&file), value_(&value), path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& message) const;

  void expect_object() const;
  // Fails on the first key not in `known`, naming `what` ("effect",
  // "parameter", ...) and listing the known keys.
  void allow_only(const std::vector<std::string>& known, std::string_view what) const;
  bool has(const std::string& key) const;
  JsonNode child(const std::string& key) const;  // fails when missing

  double number() const;                  // finite
  std::array<double, 3> vector3() const;  // [x, y, z], finite
  bool boolean() const;
  std::string string() const;
  long integer() const;

 private:
  const std::string* file_;
  const nlohmann::json* value_;
  std::string path_;
};

// Parses JSON text, refusing duplicate keys; throws MachineDescriptionError
// naming the file.
nlohmann::json parse_json_strict(const std::string& text, const std::string& file);

std::string format_number(double v);

}  // namespace truecut::sim::detail
