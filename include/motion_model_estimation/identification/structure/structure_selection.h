// Model no more than a scene needs: the bonds, their components and their types chosen from the
// markers (identify --select-structure).
//
// 1. Candidate bonds from the fitted frames: each particle's nearest neighbours by mean distance,
//    and every pair whose distance varies little (a near-rigid pair); later, pairs the residual
//    asks for (long bonds the neighbourhoods missed). Bonds already in the model stay as they are.
// 2. Candidate components in rising complexity, each level holding every component of the ones
//    before: springs; + dampers; + flexion (near-collinear triples of candidate partners: a
//    chain's bend, which springs resist only at second order); + viscosity (a drag per particle).
//    Every candidate bond (or particle) starts with a type of its own, and the equation error
//    (forces linear in k, k L, c, k theta0, c_v; gravity when the model's gravity is free) is
//    thinned by grouped backward elimination: the group (a bond's spring or flexion, its damper,
//    a particle's drag, gravity) whose removal raises the residual least goes while that rise is
//    below the Bayesian information criterion's price of its parameters; a damper never outlives
//    its bond. Bonds that come out non-physical are dropped and it runs again. A level that keeps
//    none of its new components is the structure of an earlier one and is not refitted.
//    Then, on the kept bonds of the best level so far, the non-linear level (a cubic stiffness
//    per spring, a quadratic damping per damper; rest lengths linearised and iterated,
//    Gauss-Newton), and the conditional level (on the best cumulative level's springs, a
//    threshold where the one-step residual asks for the bond to switch off, by a scan over its
//    frames sorted by length; in rounds while the residual asks for more).
// 3. Bond typing: bonds of one kind whose solved values (k, L, c; k, theta0, c; c_v) agree within
//    3 of their standard deviations share a type, kept when the criterion says the merged model
//    is as good. A type whose value comes out non-physical in the typed model's joint fit is held
//    at its bonds' weighted mean values (still counted as free) and the rest solved again.
// 4. Each level's typed model is refitted by the full identification (identifyModel) on the
//    fitted frames and judged on the held-out frames (the end of the window, never fitted): the
//    open-loop prediction error 10 frames ahead decides, the criterion breaks ties (within 2 %).
//
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/identifier.h"

namespace mme {

struct StructureCandidate;

struct StructureOptions {
  int neighbours = 8;             ///< candidate pairs: each particle's k nearest (mean distance)
  double rigid_relative_std = 0.02;  ///< ... and pairs whose distance's std / mean is below this
  int max_candidates = 600;       ///< most candidate bonds (the nearest kept)
  double held_out_share = 0.2;    ///< the window's end kept for judging (at least 15 frames)
  double type_sigmas = 3.0;       ///< bonds agreeing within this many std share a type
  bool try_dampers = true;        ///< the springs + dampers level (and dampers on flexion after it)
  bool try_flexion = true;        ///< the + flexion level (when some triple is near-collinear)
  double flexion_min_angle_rad = 2.4;  ///< a flexion candidate's mean angle at its vertex (~138 deg)
  bool try_viscosity = true;      ///< the + viscosity level
  /// The non-linear level: on the kept bonds of the best level so far, a cubic stiffness per
  /// spring (and a quadratic damping per damper), rest lengths held at the linear fit's.
  bool try_nonlinear = true;
  /// The conditional level: on the kept springs of the best cumulative level, a threshold
  /// (min_distance or max_distance) where the one-step residual asks for the bond to switch off
  /// (a cable, a contact), refined by identify's threshold search in the refit.
  bool try_conditional = true;
  bool refit = true;              ///< refit each level with identifyModel (else equation error only)
  /// The ranking refit's generation budget per level. No wall-time limit of its own (one made
  /// the chosen structure depend on the machine's load); identify.max_wall_time_s, when set,
  /// still bounds each refit.
  int refit_generations = 100;
  /// [s] wall time of the whole selection (0 = no limit), read between its steps (each removal
  /// of the elimination, each pass, each level; a refit gets what is left). Once spent, no
  /// further level starts and a level under way is given up, except the first, which ends
  /// on its elimination so far (non-physical bonds dropped, not refitted) so that there is a
  /// level to choose.
  double max_wall_time_s = 0.0;
  IdentifyOptions identify;       ///< the refits' settings
  std::function<void(const std::string&)> progress;  ///< a line per step (may be empty)
  /// Called once, on the selection's thread, as soon as the first level is judged, with that
  /// candidate (its model at the selection's rate, the data's when the model states none; the
  /// result's models carry the given model's own setting): a caller that cannot wait
  /// for the later levels (the live node) may use it at once while the selection goes on (may
  /// be empty).
  std::function<void(const StructureCandidate&)> on_first_level;
};

/// One candidate model tried.
struct StructureCandidate {
  std::string name;              ///< e.g. "springs", "springs+dampers", "springs+dampers+flexion"
  /// Not empty: this level kept none of its new components, so it is that earlier level's
  /// structure (its figures are that level's; not refitted again).
  std::string same_as;
  int bonds = 0;
  int bond_types = 0;
  int parameters = 0;            ///< free parameters
  double fit_rms_m = 0.0;        ///< equation-error residual RMS on the fitted frames [m]
  double bic = 0.0;              ///< Bayesian information criterion of that fit
  double refit_cost_m2 = -1.0;   ///< the refit's global cost (-1 when not refitted)
  /// Open-loop prediction RMS per coordinate on the held-out frames, 1, 5 and 10 frames ahead [m]
  /// (NaN when the held-out frames hold no start).
  double held_out_rms_m[3] = {0.0, 0.0, 0.0};
  bool rollout_bounded = false;
  bool chosen = false;
  Model model;                   ///< every free value set
};

struct StructureResult {
  Model model;                               ///< the chosen model, every free value set
  std::vector<StructureCandidate> candidates;  ///< every candidate tried, in the order tried
  int candidate_bonds = 0;                   ///< candidate pairs considered
  int fitted_frames = 0, held_out_frames = 0;
  /// The model-free guesses on the held-out frames, 1, 5 and 10 frames ahead [m]:
  /// constant velocity, constant acceleration, gravity only.
  double guess_rms_m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  std::vector<std::string> notes;
  bool stopped_by_time = false;              ///< max_wall_time_s cut the selection (a note says where)
};

/// A window split for judging on frames never fitted: the first frames fitted, the last
/// `held_out_share` of them (at least 15) held out. `held` is the whole window and `held_start`
/// the first held-out frame: evaluatePredictions(model, held, horizons, factor, held_start) judges
/// the held-out frames with the fitted ones as history (a marker hidden throughout the held-out
/// part is placed from them). Throws InputError (naming `who`) when fewer than 20 frames would be
/// left to fit.
struct HeldOutSplit {
  Trajectory fit, held;
  int fit_frames = 0, held_frames = 0;
  int held_start = 0;  ///< first held-out frame of `held` (= fit_frames)
};
HeldOutSplit splitHeldOut(const Trajectory& data, double held_out_share, const std::string& who);

/// Chooses the structure. `model` holds the particles (names, masses, fixed flags, gravity: free
/// gravity is a candidate like a bond) and possibly bonds that stay. `data` has the model's
/// particles as markers (by name; others ignored). Throws InputError on unusable input (too few
/// frames to hold some out, no candidate pair).
StructureResult selectStructure(const Model& model, const Trajectory& data,
                                const StructureOptions& options = {});

/// A chosen structure against a known truth (tests and benchmarks): bonds matched by their
/// particles' names.
struct StructureScore {
  double precision = 0.0, recall = 0.0, f1 = 0.0;  ///< of the two-particle bonds
  /// Of the flexion bonds (matched by vertex and ends); 1 when neither model has one.
  double flexion_precision = 1.0, flexion_recall = 1.0, flexion_f1 = 1.0;
  int viscosity_bonds = 0;         ///< viscosity bonds of the chosen model
  int types = 0;                   ///< bond types of the chosen model
  bool damped_everywhere = false;  ///< every chosen type has a non-zero damping
  bool damped_nowhere = false;     ///< no chosen type has one
  bool cubic_everywhere = false;   ///< every chosen spring type has a cubic stiffness
  bool cubic_nowhere = false;      ///< no chosen spring type has one
  /// Largest relative error of k, L (theta0), c, k_nl and c_nl of a true bond's chosen type
  /// against its true type, over the true bonds and flexions found (each term only where the
  /// truth has it).
  double max_relative_error = 0.0;
};
StructureScore scoreStructure(const Model& truth, const Model& chosen);

/// The report of every candidate as text (a table) and as CSV
/// (name,bonds,bond_types,parameters,fit_rms_m,bic,refit_cost_m2,held_out_rms_1_m,
///  held_out_rms_5_m,held_out_rms_10_m,rollout_bounded,chosen,same_as).
std::string formatStructureReport(const StructureResult& result);
std::string structureReportCsv(const StructureResult& result);

}  // namespace mme
