// The offline identification as one named pipeline: from a capture's markers to the model file,
// step by step (the model the markers give, the structure, muscles placed on springs, the
// passive identification, sensor muscles, the file's metadata). `identify` is this pipeline
// behind a command line; the benchmarks and the node's structure job call the same steps, so
// the order of the steps and what each hands to the next live here and nowhere else.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"

namespace mme {

struct PipelineResult;

/// Which steps run and how. Each optional step runs when its options are set.
struct PipelineOptions {
  IdentifyOptions identify;  ///< the passive identification (also the structure's refits)
  /// Choose the bonds from the markers first (structure_selection.h), within
  /// identify.max_wall_time_s.
  bool select_structure = false;
  /// Turn the model's plain spring types into muscles before the identification
  /// (muscle_placement.h).
  std::optional<MusclePlacement> muscles;
  /// Fit sensor muscles on the identified model last (sensor_muscles.h); kept only where they
  /// predict the held-out frames better than the passive model.
  std::optional<SensorMuscleOptions> sensor_muscles;
  /// With sensor muscles: the passive identification defers an output error that cannot pay
  /// off (IdentifyOptions::defer_output_error_on_misfit: one-step residuals over 2x what the
  /// markers' noise gives), and the pipeline runs it after the muscles only when they are not kept
  /// (runDeferredOutputError). false: it runs before the muscles as identifyModel decides.
  /// Off by default: where the output error's answer is adopted, the muscles fitted on it can
  /// predict the held-out frames better than those fitted on the one-step answer
  /// (docs/real_recordings.md, *The output error deferred*).
  bool output_error_after_muscles = false;
  /// One line per step for a person (the structure's levels, the muscles' steps); may be empty.
  std::function<void(const std::string&)> say;
  /// Something the user should know that does not stop the run (e.g. muscles not kept); may be
  /// empty.
  std::function<void(const std::string&)> warn;
  /// After every generation of the passive identification (identifyModel); may be empty.
  std::function<void(const Progress&)> progress;
  /// Right after the structure step, before anything else runs (e.g. to keep its report should
  /// the run be stopped later); may be empty.
  std::function<void(const StructureResult&)> structure_chosen;
  /// With the model and data the passive identification is about to search; may be empty.
  std::function<void(const Model&, const Trajectory&)> identification_starts;
  /// Right after the passive identification, before the sensor muscles, with the result so far
  /// (`model` the passive model with its initial state): e.g. to write the passive model first,
  /// so that a long or interrupted muscle fit leaves a usable file. May be empty.
  std::function<void(const PipelineResult&)> passive_identified;
  /// Raised by another thread or a signal handler (e.g. Ctrl-C): the step under way ends as
  /// soon as it can with its best so far (the structure as when its time limit is spent, the
  /// passive search after its generation), and no later step starts except the passive
  /// identification's (so that there is a model to write). May be null.
  const std::atomic<bool>* cancel = nullptr;
};

/// "" when the options can run, else what is wrong, naming the option.
std::string validateOptions(const PipelineOptions& options);

/// What every step left.
struct PipelineResult {
  Model model;  ///< what the file gets: the identified model, with sensor muscles where kept
  std::optional<StructureResult> structure;  ///< the structure step's report
  int muscle_types = 0;                      ///< spring types the muscles step turned into muscles
  IdentifyResult identified;                 ///< the passive identification
  std::optional<SensorMuscleResult> sensor_muscles;  ///< the sensor muscles' fit, when it ran
  std::string sensor_muscle_summary;  ///< one line on that fit (empty when it did not run)
  std::vector<std::string> notes;     ///< written into the file's `identification: notes:`
  bool cancelled = false;             ///< PipelineOptions::cancel cut the run short
};

// ------------------------------------------------------------------ the steps, in order

/// Step 1 without a model file: the markers are the particles (1 kg each, free gravity; no
/// bonds), for the structure step to add them (marker_model.h).
Model startingModel(const Trajectory& data);

/// Step 2: the structure chosen from the markers; the model's own bonds stay.
/// `trajectory` holds the model's particles as markers (remapMarkers). `on_first_level`, when
/// set, hears the first level as soon as it is judged (the live node starts on it while the
/// later levels are judged).
StructureResult chooseStructure(const Model& model, const Trajectory& trajectory,
                                const PipelineOptions& options,
                                std::function<void(const StructureCandidate&)> on_first_level = {});

/// Step 3: plain spring types become muscle types reading their nearest bonds. InputError when
/// the model has no spring type that can become a muscle.
Model placeMuscles(const Model& model, const Trajectory& trajectory, const MusclePlacement& placement);

/// Step 4: the passive identification (identifyModel with the options' progress).
IdentifyResult identifyPassive(const Model& model, const Trajectory& trajectory,
                               const PipelineOptions& options);

/// Step 5: sensor muscles on the identified model; on data they cannot use (too few frames, no
/// pair seen together often enough) nothing, with the reason in `result->notes` and warned.
/// Fills result->sensor_muscles, sensor_muscle_summary and, where kept, result->model.
void fitSensorMuscleStep(const Trajectory& trajectory, const PipelineOptions& options,
                         PipelineResult* result);

/// Step 5b: the output error the passive identification deferred
/// (PipelineOptions::output_error_after_muscles), run when the sensor muscles did not replace
/// the passive model; its answer, where adopted, becomes `result->identified` and the model.
void deferredOutputErrorStep(const Trajectory& trajectory, const PipelineOptions& options,
                             PipelineResult* result);

/// Step 6: the particles' initial state from frame `frame` of `trajectory` (which holds the
/// model's particles as markers, remapMarkers), so that the model plays from where the data
/// are: a free particle seen there starts at its position [m] and, when also seen in the next
/// frame, with the velocity [m/s] that makes one simulated frame land on it (the frame
/// difference corrected for the integrator; the frame difference itself when the model cannot
/// be simulated); fixed particles (anchors, ground points) and particles not seen keep the
/// model's. InputError when `frame` is outside the data.
void startAtFrame(const Trajectory& trajectory, int frame, Model* model);

/// Step 7, the judge (not run by runPipeline: what to judge on is the caller's choice): the
/// model's open-loop predictions `horizon_frames` ahead on `data`'s frames from
/// `first_judged_frame` on (the frames before it are history only, e.g. the fitted frames
/// before held-out ones), beside the model-free guesses on the same samples, and whether its
/// long rollout stays bounded. `data`'s markers are matched to the model's particles by name, so
/// `data` may be the capture itself; particles without a marker (the sensor muscles' anchors)
/// are unseen. InputError when nothing can be judged (no frame after the history, no rate).
PredictionReport judgePredictions(const Model& model, const Trajectory& data, int first_judged_frame,
                                  int horizon_frames = 10);

/// Every step the options ask for, in order, from `model` (a model file's, or startingModel's)
/// and the trajectory matched to its particles.
PipelineResult runPipeline(const Model& model, const Trajectory& trajectory,
                           const PipelineOptions& options);

}  // namespace mme
