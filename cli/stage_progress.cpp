#include "stage_progress.hpp"

#include <cstdio>

namespace truecut::cli {

StageProgress::StageProgress(std::string command, bool enabled)
    : command_(std::move(command)), start_(std::chrono::steady_clock::now()) {
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
}

void StageProgress::message(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (shown_) std::fputs("\n", stderr);
  shown_ = false;
  std::fputs(line.c_str(), stderr);
}

void StageProgress::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stop_; })) {
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (s < 1.0) continue;
    // Padded so that a shorter stage name overwrites a longer one.
    std::fprintf(stderr, "\r%s: %-40s (%.0f s)", command_.c_str(), stage_.c_str(), s);
    std::fflush(stderr);
    shown_ = true;
  }
}

}  // namespace truecut::cli
