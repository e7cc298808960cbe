// Structure selection (structure_selection.h): the sequence of its steps. The model and data are
// checked and split into fitted and held-out frames; candidates are proposed from the fitted
// frames' geometry; the levels are fitted, refitted and judged in order (level_sequence.h);
// the level that predicts the held-out frames best is chosen. Each step lives in its own unit
// in this folder; this file only orders them.
#include "motion_model_estimation/identification/structure/structure_selection.h"

#include <array>
#include <cstdio>
#include <set>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "candidate_structure.h"
#include "deadline.h"
#include "level_judging.h"
#include "level_sequence.h"
#include "selection_context.h"

namespace mme {

namespace {

using structure::SelectionContext;

/// `given` with the data's rate when it states none (a live window, a model of particles
/// alone); throws InputError when neither states one.
Model withFrameRate(const Model& given, const Trajectory& data) {
  Model model = given;
  if (!(model.frame_rate_hz > 0.0)) model.frame_rate_hz = data.frame_rate_hz;
  if (!(model.frame_rate_hz > 0.0))
    throw InputError("structure selection: no frame rate (neither the model nor the data state one)");
  return model;
}

/// Throws InputError when the model holds what the selection cannot weigh: interactions, or
/// muscles (pruning renumbers bonds, which a muscle's input list would not follow; and a
/// muscle's network is not linear, so the equation error this selection rests on cannot weigh
/// it).
void requireSelectable(const Model& model) {
  if (!model.interactions.empty())
    throw InputError("structure selection: the model has interactions (bonds found on the fly); "
                     "give the particles and fixed bonds only");
  for (const BondType& type : model.bond_types)
    if (bondKindInfo(type.kind).network)
      throw InputError("structure selection: the model has muscles (type '" + type.name +
                       "'); select the passive structure first, then add the muscles");
}

/// The equation error's kinematics: raw differences (exact on noiseless data with one step per
/// frame) unless the markers' noise is estimated at 1 um or more (real captures: 10 um to
/// 1 mm): then smoothed. (Not the identifier's test of an exact one-step fit: with bonds still
/// missing from the candidates no fit is exact.)
EquationErrorOptions equationErrorKinematics(const SelectionContext& ctx) {
  EquationErrorOptions ee;
  const double noise_m = estimateMarkerNoise(ctx.fit);
  if (noise_m >= 1e-6) ee.smoothing_half_width = 4;
  char line[160];
  std::snprintf(line, sizeof(line), "structure: marker noise estimated %.3g m; equation error on %s kinematics",
                noise_m, ee.smoothing_half_width > 0 ? "smoothed" : "raw");
  ctx.say(line);
  return ee;
}

/// The candidate pairs of the fitted frames, counted in `ctx.result`; throws InputError when
/// there is none.
std::vector<std::pair<int, int>> proposePairs(const SelectionContext& ctx) {
  const std::vector<std::pair<int, int>> pairs = structure::candidatePairs(ctx.model, ctx.fit, ctx.options);
  ctx.result->candidate_bonds = static_cast<int>(pairs.size());
  if (pairs.empty()) throw InputError("structure selection: no candidate pair of particles");
  ctx.say("structure: " + std::to_string(pairs.size()) + " candidate bonds among " +
          std::to_string(ctx.model.particles.size()) + " particles; " + std::to_string(ctx.split.fit_frames) +
          " frames fitted, " + std::to_string(ctx.split.held_frames) + " held out");
  return pairs;
}

/// Flexion candidates on near-collinear triples of the candidate pairs (none unless asked for).
std::vector<std::array<int, 3>> proposeTriples(const SelectionContext& ctx,
                                               const std::vector<std::pair<int, int>>& pairs) {
  if (!ctx.options.try_flexion) return {};
  return structure::candidateTriples(ctx.model, ctx.fit, pairs, 4, ctx.options.flexion_min_angle_rad,
                                     4 * static_cast<int>(ctx.model.particles.size()));
}

/// Marks the best candidate chosen and hands every candidate's model the caller's frame rate.
void choose(std::vector<StructureCandidate> candidates, double frame_rate_hz, StructureResult* result) {
  const int chosen = structure::bestCandidate(candidates);
  candidates[chosen].chosen = true;
  for (StructureCandidate& c : candidates) c.model.frame_rate_hz = frame_rate_hz;
  result->model = candidates[chosen].model;
  result->candidates = std::move(candidates);
}

}  // namespace

HeldOutSplit splitHeldOut(const Trajectory& data, double held_out_share, const std::string& who) {
  const int frames = data.numFrames();
  HeldOutSplit split;
  split.held_frames = std::max(15, static_cast<int>(std::lround(held_out_share * frames)));
  split.fit_frames = frames - split.held_frames;
  if (split.fit_frames < 20)
    throw InputError(who + ": " + std::to_string(frames) + " frames are too few (need at least " +
                     std::to_string(20 + split.held_frames) + ": 20 to fit, " +
                     std::to_string(split.held_frames) + " held out)");
  split.fit = sliceFrames(data, 0, split.fit_frames);
  split.held = data;
  split.held_start = split.fit_frames;
  return split;
}

StructureResult selectStructure(const Model& given, const Trajectory& data,
                                const StructureOptions& options) {
  const Model model = withFrameRate(given, data);
  const structure::Deadline deadline(options.max_wall_time_s, options.identify.cancel);
  requireSelectable(model);
  const HeldOutSplit split = splitHeldOut(data, options.held_out_share, "structure selection");
  StructureResult result;
  result.fitted_frames = split.fit_frames;
  result.held_out_frames = split.held_frames;
  SelectionContext ctx(model, options, split, deadline, &result);
  const std::vector<std::pair<int, int>> pairs = proposePairs(ctx);
  structure::judgeModelFreeGuesses(model, split, &result);
  ctx.ee = equationErrorKinematics(ctx);
  ctx.first_candidate_type = static_cast<int>(model.bond_types.size());
  const std::vector<std::array<int, 3>> triples = proposeTriples(ctx, pairs);
  std::vector<structure::Level> levels = structure::cumulativeLevels(options, !triples.empty());
  ctx.say("structure: " + std::to_string(triples.size()) + " flexion candidate(s) on near-collinear triples; " +
          std::to_string(levels.size()) + " level(s) to try");
  choose(structure::runLevels(ctx, std::move(levels), triples,
                              std::set<std::pair<int, int>>(pairs.begin(), pairs.end())),
         given.frame_rate_hz, &result);
  return result;
}

}  // namespace mme
