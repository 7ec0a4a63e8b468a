#include "field_source.hpp"

#include <algorithm>
#include <stdexcept>

#include "truecut/rt/field_file.hpp"

namespace truecut::rt::comp {

std::unique_ptr<const rt::CorrectionField> load_field(const std::string& path,
                                                      const std::vector<int32_t>& required_tools) {
  rt::LoadedField loaded = rt::read_field_file(path);
  const auto tools = loaded.field.tools();
  for (int32_t t : required_tools)
    if (!std::binary_search(tools.begin(), tools.end(), t))
      throw std::runtime_error(path + ": no layer for tool " + std::to_string(t) +
                               " (required by tools=)");
  return std::make_unique<const rt::CorrectionField>(std::move(loaded.field));
}

void FieldSource::load_now() {
  unpublished_ = load_field(path_, required_tools_);
  if (!handover_.publish(unpublished_)) throw std::runtime_error(path_ + ": hand-over queue full");
}

std::string FieldSource::service() {
  handover_.collect_retired();
  std::string error;
  const uint32_t requested = requests_.load(std::memory_order_acquire);
  if (requested != served_) {
    served_ = requested;
    try {
      if (path_.empty()) throw std::runtime_error("no field file to reload (load with field=FILE)");
      unpublished_ = load_field(path_, required_tools_);  // replaces one not yet published
    } catch (const std::exception& e) {
      errors_.fetch_add(1, std::memory_order_relaxed);
      error = e.what();
    }
  }
  if (unpublished_) (void)handover_.publish(unpublished_);  // retried next time when full
  return error;
}

}  // namespace truecut::rt::comp
