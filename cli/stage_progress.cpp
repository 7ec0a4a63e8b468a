#include "stage_progress.hpp"

#include <cstdio>
#include <cstdlib>

namespace truecut::cli {

namespace {

// $TRUECUT_PROGRESS_AFTER_S (seconds, 0 to 3600; default 1): how long a
// command runs before its stage is shown. 0 shows each stage as it starts,
// which lets a test see the line of a command that takes less than a second.
double shown_after_s() {
  const char* env = std::getenv("TRUECUT_PROGRESS_AFTER_S");
  if (!env || !*env) return 1.0;
  char* end = nullptr;
  const double s = std::strtod(env, &end);
  return *end == '\0' && s >= 0 && s <= 3600 ? s : 1.0;
}

}  // namespace

StageProgress::StageProgress(std::string command, bool enabled)
    : command_(std::move(command)),
      start_(std::chrono::steady_clock::now()),
      after_s_(shown_after_s()),
      enabled_(enabled) {
  if (enabled) thread_ = std::thread([this] { run(); });
}

StageProgress::~StageProgress() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (shown_) std::fputs("\n", stderr);
}

void StageProgress::stage(std::string what) {
  std::lock_guard<std::mutex> lock(mutex_);
  stage_ = std::move(what);
  if (after_s_ == 0) draw_if_due();
}

void StageProgress::message(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (shown_) std::fputs("\n", stderr);
  shown_ = false;
  std::fputs(line.c_str(), stderr);
}

void StageProgress::draw_if_due() {
  if (!enabled_ || stage_.empty()) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (s < after_s_) return;
  // Padded so that a shorter stage name overwrites a longer one.
  std::fprintf(stderr, "\r%s: %-40s (%.0f s)", command_.c_str(), stage_.c_str(), s);
  std::fflush(stderr);
  shown_ = true;
}

void StageProgress::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stop_; }))
    draw_if_due();
}

}  // namespace truecut::cli
