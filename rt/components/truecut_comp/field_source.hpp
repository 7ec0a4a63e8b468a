// The non-real-time half of truecut_comp's field hand-over: reads and
// validates a .tcf file, publishes the field to the servo thread through a
// Handover, and frees the fields the servo thread retires. Runs in init and
// in the component's service, never in the servo thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "truecut/rt/channel.hpp"
#include "truecut/rt/core/correction_field.hpp"

namespace truecut::rt::comp {

using FieldHandover = rt::Handover<rt::CorrectionField>;

// Reads `path` (read_field_file checks magic, version, frame = workpiece,
// units = mm, checksum, grid and layers) and checks that every tool in
// `required_tools` has a layer. Throws std::runtime_error naming the file.
std::unique_ptr<const rt::CorrectionField> load_field(const std::string& path,
                                                      const std::vector<int32_t>& required_tools);

class FieldSource {
 public:
  FieldSource(std::string path, std::vector<int32_t> required_tools)
      : path_(std::move(path)), required_tools_(std::move(required_tools)) {}

  const std::string& path() const { return path_; }
  FieldHandover& handover() { return handover_; }

  // Servo thread: asks for the file to be read again. Wait-free.
  void request_reload() noexcept { requests_.fetch_add(1, std::memory_order_release); }
  // Servo thread: failed loads so far.
  int32_t load_errors() const noexcept { return errors_.load(std::memory_order_relaxed); }

  // Non-RT: loads now and publishes (init time). Throws on a bad file.
  void load_now();
  // Non-RT, the component's service: frees retired fields, serves a pending
  // reload request, publishes what could not be published yet. Never throws;
  // returns an error text for a failed load (empty if none).
  std::string service();

 private:
  std::string path_;
  std::vector<int32_t> required_tools_;
  FieldHandover handover_;
  std::atomic<uint32_t> requests_{0};
  uint32_t served_ = 0;
  std::atomic<int32_t> errors_{0};
  std::unique_ptr<const rt::CorrectionField> unpublished_;
};

}  // namespace truecut::rt::comp
