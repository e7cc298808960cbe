#include "motion_model_estimation/live/structure_job.h"

#include <algorithm>
#include <exception>
#include <utility>

namespace mme {

namespace {
constexpr int kSelectionMinFrames = 35;  ///< selectStructure: 20 fitted + 15 held out
}

StructureJob::StructureJob(Model base, PipelineOptions options, int min_frames, bool request_first)
    : base_(std::move(base)), options_(std::move(options)),
      min_frames_(std::max(min_frames, kSelectionMinFrames)), requested_(request_first),
      state_(request_first ? State::kPending : State::kIdle) {}

void StructureJob::request() {
  std::lock_guard<std::mutex> lock(mutex_);
  requested_ = true;
  if (state_ != State::kRunning) state_ = State::kPending;
}

bool StructureJob::pending() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return requested_;
}

std::optional<StructureResult> StructureJob::runIfDue(const Trajectory& window, const FirstLevel& first_level) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!requested_ || window.numFrames() < min_frames_) return std::nullopt;
    requested_ = false;
    state_ = State::kRunning;
  }
  try {
    // The pipeline's structure step, with the first level passed on.
    std::function<void(const StructureCandidate&)> on_first_level;
    if (first_level)
      on_first_level = [this, &first_level](const StructureCandidate& c) {
        Model model = c.model;
        model.frame_rate_hz = base_.frame_rate_hz;
        first_level(model, c.name);
      };
    StructureResult result = chooseStructure(base_, window, options_, std::move(on_first_level));
    std::string level;
    for (const StructureCandidate& c : result.candidates)
      if (c.chosen) level = c.name;
    std::lock_guard<std::mutex> lock(mutex_);
    state_ = requested_ ? State::kPending : State::kChosen;
    level_ = level;
    ++selections_;
    last_cut_ = result.stopped_by_time;
    error_.clear();
    return result;
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    state_ = requested_ ? State::kPending : State::kFailed;
    error_ = e.what();
    return std::nullopt;
  }
}

bool StructureJob::choseFirstLevel(const StructureResult& result) {
  if (result.candidates.empty()) return false;
  const StructureCandidate& first = result.candidates.front();
  for (const StructureCandidate& c : result.candidates)
    if (c.chosen) return &c == &first || c.same_as == first.name;
  return false;
}

StructureJob::State StructureJob::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

std::string StructureJob::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (state_) {
    case State::kIdle: return "idle";
    case State::kPending: return "pending";
    case State::kRunning: return "running";
    case State::kChosen: return "chosen:" + level_;
    case State::kFailed: return "failed";
  }
  return "?";
}

bool StructureJob::lastCut() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_cut_;
}

std::string StructureJob::lastError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

uint32_t StructureJob::selections() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return selections_;
}

}  // namespace mme
