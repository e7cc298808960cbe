// identify's option table: what parses its command line and what `identify --help` prints
// (docs/tools.md follows it).
#pragma once

#include "cli_args.h"

namespace mme {

/// identify's search options (the evolution strategy and the islands).
inline CliGroup identifySearchOptions() {
  return {"Search",
   {{"preset", "NAME", "default",
     "default: the measured best settings; paper: the paper's method (random starts, its "
     "bounds, one-step cost, the whole generation budget)."},
    {"method", "NAME", "es", "The search method; es (evolution strategy) is the only one."},
    {"generations", "N", "1000", "The generation budget of the evolution strategy."},
    {"population", "P", "100", "Individuals per generation."},
    {"patience", "G", "50 (paper: 0)",
     "Stop once the best cost fell by less than 1e-4 (relative) over G generations; 0 runs "
     "the whole budget."},
    {"target-cost", "C", "0 (never)", "Stop once the cost [m^2] is at most C."},
    {"max-time-s", "S", "0 (no limit)",
     "Wall-time limit [s] of the structure selection (all its levels) and then of the "
     "passive identification; a cut selection keeps the best level judged so far."},
    {"seed", "S", "1", "Random seed: the same seed, input and --threads give the same result."},
    {"threads", "T", "1", "Threads evaluating the population (with --islands: shared by the islands)."},
    {"islands", "N", "1",
     "Island model: N populations of --population each, own seeds, stepping in lock-step in "
     "this process (threads, deterministic); the best island's best is the answer."},
    {"island-processes", "", "",
     "With --islands N: each island in a child process of its own (this host), migrants "
     "passed through this process; the same result as threads, bit for bit."},
    {"migration-period", "G", "10", "Islands: generations between migrations."},
    {"migrants", "K", "2", "Islands: best individuals each island sends to every other island per migration."}}};
}

/// identify's structure-selection and muscle options.
inline CliGroup identifyStructureAndMuscleOptions() {
  return {"Structure and muscles",
   {{"select-structure", "", "",
     "Choose the bonds from the markers (springs, dampers, flexion, nonlinear and "
     "conditional levels, judged on held-out frames); without --model the markers are the "
     "particles. Writes the levels' report to OUT.yaml.structure.csv."},
    {"sensor-muscles", "auto|off|SENSORS", "auto (off with --preset paper or --compare-to-model)",
     "Sensor muscles after the passive model, kept only where they predict held-out frames "
     "better. auto: reading 16 bonds each, but not started where the passive model already "
     "predicts at the markers' noise or its one-step residual is only noise (the reason is "
     "printed and noted in the file); off (or 0): a plain passive model; SENSORS: reading "
     "SENSORS bonds each, always fitted. They add three anchor particles far from the body "
     "(with anchors)."},
    {"muscles-max-time-s", "S", "0 (no limit)",
     "Wall-time limit [s] of the sensor muscles' search (checked between its steps)."},
    {"muscle-neighbours", "K", "2", "Sensor muscles: neighbour muscles per particle."},
    {"rollout-rounds", "R", "3", "Sensor muscles: rounds of rollout equations (0..20)."},
    {"muscle-anchors", "auto|0|1", "auto",
     "Sensor muscles: anchors far from the body (1), none (0), or the layout predicting the "
     "validation frames better (auto)."},
    {"anchor-stiffness", "1|0|auto", "1",
     "Sensor muscles: the anchor muscles' own stiffness fitted (1), held at 0 (0), or held at "
     "0 for a travelling body (auto)."},
    {"add-muscles", "INPUTS", "off (2 when --muscle-hidden is given)",
     "Turn the model's plain spring types into muscles reading INPUTS nearest bonds."},
    {"muscle-hidden", "H", "0", "Hidden units of those muscles' networks."}}};
}

inline CliSpec identifyCliSpec() {
  CliSpec s;
  s.tool = "identify";
  s.synopsis = "--trajectory FILE(.trc|.c3d|.bag) --out OUT.yaml (--model M.yaml | --select-structure) "
               "[options]";
  s.purpose =
      "Identifies a mass-spring model of a marker capture: the free parameters of --model's "
      "bonds, or with --select-structure the bonds themselves, chosen from the markers. Writes a "
      "plain passive model to --out as soon as it is identified (before any sensor muscles), "
      "with the first used frame's positions and velocities as the particles' initial state. "
      "Ctrl-C (SIGINT) or SIGTERM ends the step under way and writes the best model so far "
      "(exit 130 / 143); a second Ctrl-C stops at once.";
  s.groups = {
      {"Input and output",
       {{"trajectory", "FILE", "", "The capture: a TRC, C3D or bag file (required)."},
        {"topic", "T", "the bag's only MarkerFrame topic", "The bag topic to read."},
        {"model", "M.yaml", "none",
         "The model file whose free parameters are identified; its particle names are marker "
         "names. Not needed with --select-structure (the markers become the particles)."},
        {"out", "OUT.yaml", "", "The identified model file to write (required)."},
        {"compare-to-model", "", "",
         "Treat --model's values as the truth: the table adds the true value and the error %."},
        {"quiet", "", "", "No progress lines (warnings and the result are still printed)."}}},
      {"Frames",
       {{"first-frame", "F", "0",
         "The first frame used, counted from 0 (not by the file's Frame# column, which often starts at 1)."},
        {"frames", "N", "every frame from --first-frame on", "How many frames to use."},
        {"window-frames", "W", "no limit", "At most this many frames (an upper bound on --frames)."}}},
      identifySearchOptions(),
      {"Cost and refinement",
       {{"cost", "NAME", "auto (paper: short_term)",
         "auto: the output error when the markers look noisy, else the one-step cost; "
         "short_term: the paper's one-step prediction; output_error: multiple shooting."},
        {"segment-frames", "K", "10", "The output error's frames per shooting segment."},
        {"grow-segments", "G", "0 (one fit on every frame)",
         "The output error first fits G segments, then twice as many, and so on."},
        {"refine", "NAME", "levenberg_marquardt (paper: bobyqa)",
         "Local refinement of the best individual: bobyqa, newuoa, praxis or "
         "levenberg_marquardt."},
        {"refine-start", "G", "5 (paper: 400)", "The first generation with a refinement."},
        {"refine-period", "G", "5 (paper: 100)", "Generations between refinements (0: never)."}}},
      identifyStructureAndMuscleOptions(),
  };
  s.examples = {
      "identify --trajectory capture.trc --select-structure --out capture_model.yaml",
      "identify --model arm.yaml --trajectory arm.trc --first-frame 100 --frames 500 --out arm_id.yaml",
      "identify --trajectory walk.c3d --select-structure --max-time-s 600 --sensor-muscles 16 "
      "--muscles-max-time-s 300 --out walk_model.yaml",
  };
  s.next_step =
      "evaluate --model OUT.yaml --trajectory FILE judges how well the model predicts; "
      "simulate --model OUT.yaml --frames N --out play.trc plays it from the first used frame "
      "(simulate --trajectory FILE --start-frame F from another frame); "
      "replay.launch shows a model in rviz (docs/node.md).";
  return s;
}

}  // namespace mme
