// The order of levels in structure selection (level_sequence.h): the cumulative levels, the
// non-linear and conditional levels planned from the judged ones, and the time limit between
// levels.
#include "level_sequence.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "level_judging.h"

namespace mme {
namespace structure {

namespace {

/// Runs the levels and keeps what the later levels need of the earlier ones.
class LevelSequence {
 public:
  LevelSequence(const SelectionContext& ctx, std::vector<Level> levels,
                const std::vector<std::array<int, 3>>& triples, std::set<std::pair<int, int>> all_candidates)
      : ctx_(ctx), levels_(std::move(levels)), triples_(triples),
        all_candidates_(std::move(all_candidates)), cumulative_levels_(levels_.size()) {}

  std::vector<StructureCandidate> run() {
    const auto start = std::chrono::steady_clock::now();
    for (size_t level_index = 0; level_index < levels_.size(); ++level_index) {
      if (!runLevel(level_index)) break;
      const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
      sayPace(level_index, elapsed.count());
      if (level_index == 0 && ctx_.options.on_first_level) ctx_.options.on_first_level(candidates_.front());
    }
    return std::move(candidates_);
  }

 private:
  /// After a level: how many of the levels planned so far are done and the time the rest would
  /// take at the pace so far (later levels have more unknowns: a lower bound more than a
  /// promise; the time limit, when set, cuts it).
  void sayPace(size_t level_index, double elapsed_s) const {
    const size_t done = level_index + 1, left = levels_.size() - done;
    char line[160];
    std::snprintf(line, sizeof(line), "structure: %zu of %zu level(s) done in %.0f s%s", done,
                  levels_.size(), elapsed_s, left == 0 ? "" : ", about ");
    std::string text = line;
    if (left > 0) {
      std::snprintf(line, sizeof(line), "%.0f s more at this pace", elapsed_s / done * left);
      text += line;
    }
    ctx_.say(text);
  }

  /// Fits, refits and judges one level and plans the levels it calls for; false when the time
  /// limit stopped the sequence. Once the time limit is spent, no further level starts; a level
  /// under way is given up unless it is the first (which ends on its elimination so far:
  /// something to choose).
  bool runLevel(size_t level_index) {
    const Level level = levels_[level_index];  // a copy: planning appends to levels_
    if (!candidates_.empty() && ctx_.deadline.passed()) {
      stopByTime("before " + level.name);
      return false;
    }
    const LevelInputs in{untyped_, conditional_choices_, triples_, &all_candidates_};
    LevelFit fit = fitLevel(ctx_, level, in, candidates_.empty());
    if (fit.given_up) {
      stopByTime("during " + level.name);
      return false;
    }
    const bool conditional = level.conditional_on >= 0;
    record(std::move(fit), level.nonlinear_on >= 0, conditional);
    planConditionalLevel(level_index, conditional);
    planNonlinearLevel(level_index);
    return true;
  }

  /// Keeps a fitted level. A level that kept none of its new components has an earlier level's
  /// structure: not refitted nor judged again (its figures are that level's).
  void record(LevelFit fit, bool nonlinear, bool conditional) {
    untyped_.push_back(fit.kept_untyped);
    base_sigma2_.push_back(fit.sigma2);
    base_rows_.push_back(fit.rows);
    StructureCandidate& cand = fit.candidate;
    const size_t same = std::find(signatures_.begin(), signatures_.end(), fit.signature) - signatures_.begin();
    signatures_.push_back(fit.signature);
    if (same + 1 < signatures_.size()) {
      const StructureCandidate& earlier = candidates_[same];
      const std::string name = cand.name;
      cand = earlier;
      cand.name = name;
      cand.same_as = earlier.same_as.empty() ? earlier.name : earlier.same_as;
      ctx_.say("structure: " + name + ": none of its new components kept; the structure of " + cand.same_as);
      candidates_.push_back(std::move(cand));
      untyped_.back() = untyped_[same];
    } else {
      refitAndJudge(ctx_, &cand, nonlinear, conditional);
      candidates_.push_back(std::move(cand));
    }
  }

  /// The candidate whose structure `index` has (itself, or the level it is the same as).
  int structureOf(int index) const {
    if (candidates_[index].same_as.empty()) return index;
    return static_cast<int>(std::find_if(candidates_.begin(), candidates_.end(),
                                         [&](const StructureCandidate& c) { return c.name == candidates_[index].same_as; }) -
                            candidates_.begin());
  }

  /// After the cumulative levels and the non-linear one: conditions on the best cumulative
  /// level's springs, where the one-step residual asks for a switch; then again on that
  /// conditional level's result while the residual asks for more (at most 4 rounds: a wrong
  /// condition on one bond biases its neighbours' fits, hiding theirs at first).
  void planConditionalLevel(size_t level_index, bool conditional) {
    const bool first_round = level_index + 1 == cumulative_levels_ + (ctx_.options.try_nonlinear ? 1 : 0);
    const bool next_round = conditional && ++conditional_rounds_ < 4 && candidates_.back().same_as.empty();
    if (!((first_round || next_round) && ctx_.options.try_conditional)) return;
    int base = static_cast<int>(level_index);
    if (first_round) {
      std::vector<StructureCandidate> linear(candidates_.begin(), candidates_.begin() + cumulative_levels_);
      base = structureOf(bestCandidate(linear));
    }
    const double price_m2 = base_sigma2_[base] * std::log(static_cast<double>(std::max<size_t>(base_rows_[base], 2)));
    conditional_choices_ = conditionalCandidates(untyped_[base], ctx_.fit, ctx_.first_candidate_type, 20.0 * price_m2);
    ctx_.say("structure: " + std::to_string(conditional_choices_.size()) + " spring(s) of " + candidates_[base].name +
             " whose residual asks for a switching condition");
    if (conditional_choices_.empty()) return;
    Level next{first_round ? candidates_[base].name + "+conditional" : candidates_[base].name,
               levels_[base].dampers, levels_[base].flexion, levels_[base].viscosity};
    if (!first_round) next.name += "+";
    next.conditional_on = base;
    levels_.push_back(next);
  }

  /// After the cumulative levels: the non-linear terms on the best of them.
  void planNonlinearLevel(size_t level_index) {
    if (!(level_index + 1 == cumulative_levels_ && ctx_.options.try_nonlinear)) return;
    const int base = structureOf(bestCandidate(candidates_));
    levels_.push_back({candidates_[base].name + "+nonlinear", levels_[base].dampers, levels_[base].flexion,
                       levels_[base].viscosity, base});
  }

  void stopByTime(const std::string& where) {
    ctx_.result->stopped_by_time = true;
    char line[200];
    if (ctx_.deadline.cancelled())
      std::snprintf(line, sizeof(line), "interrupted: the selection stopped %s after %zu level(s) "
                    "(%.1f s): the best level judged so far is chosen",
                    where.c_str(), candidates_.size(), ctx_.deadline.elapsedS());
    else
      std::snprintf(line, sizeof(line), "the time limit (%.3g s) stopped the selection %s after %zu "
                    "level(s) (%.1f s): the best level judged so far is chosen",
                    ctx_.deadline.maxS(), where.c_str(), candidates_.size(), ctx_.deadline.elapsedS());
    ctx_.say(std::string("structure: ") + line);
    ctx_.result->notes.push_back(line);
  }

  const SelectionContext& ctx_;
  std::vector<Level> levels_;
  const std::vector<std::array<int, 3>>& triples_;
  std::set<std::pair<int, int>> all_candidates_;
  const size_t cumulative_levels_;
  std::vector<StructureCandidate> candidates_;
  std::vector<std::string> signatures_;  ///< per level: the kept structure before typing
  std::vector<Model> untyped_;           ///< per level: the kept bonds, one type each, values set
  std::vector<ConditionalChoice> conditional_choices_;  ///< the conditional level's thresholds
  int conditional_rounds_ = 0;
  std::vector<double> base_sigma2_;      ///< per level: its noise level (the criterion's sigma^2)
  std::vector<size_t> base_rows_;        ///< ... and its equations
};

}  // namespace

std::vector<Level> cumulativeLevels(const StructureOptions& options, bool with_flexion) {
  std::vector<Level> levels = {{"springs", false, false, false}};
  if (options.try_dampers) levels.push_back({"springs+dampers", true, false, false});
  if (with_flexion) levels.push_back({levels.back().name + "+flexion", options.try_dampers, true, false});
  if (options.try_viscosity)
    levels.push_back({levels.back().name + "+viscosity", options.try_dampers, with_flexion, true});
  return levels;
}

std::vector<StructureCandidate> runLevels(const SelectionContext& ctx, std::vector<Level> levels,
                                          const std::vector<std::array<int, 3>>& triples,
                                          std::set<std::pair<int, int>> all_candidates) {
  return LevelSequence(ctx, std::move(levels), triples, std::move(all_candidates)).run();
}

}  // namespace structure
}  // namespace mme
