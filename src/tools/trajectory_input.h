// The trajectory a tool works on, the same way for every tool: read, matched to the model's
// particles, cut to the frames asked for, its frame rate resolved.
#pragma once

#include <string>

#include "cli_args.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Reads `path` (.trc, .c3d, or a .bag with MarkerFrame on `topic`), keeps the model's particles
/// as markers in model order (a free particle missing from the file: InputError naming it; a
/// fixed one stays unseen, where the model holds it, e.g. sensor muscles' anchors), keeps the
/// frames --first-frame / --frames / --window-frames of `args` ask for, and fills in the model's
/// frame rate from the data when it has none. The reader's warnings and a rate mismatch go to
/// stderr as "TOOL: warning: ...". With `history` > 0, up to that many frames before
/// --first-frame are kept in front too (as many as there are: `*history_kept`). `model_only`,
/// when given, gets the number of the model's particles the file has no marker for (fixed
/// points of the model only, such as sensor muscles' anchors): not markers of the capture.
Trajectory loadModelTrajectory(const char* tool, const std::string& path, const std::string& topic,
                               const CliArgs& args, Model* model, int history = 0,
                               int* history_kept = nullptr, int* model_only = nullptr);

/// The two halves of loadModelTrajectory: the file read (any kind; warnings to stderr), and the
/// data matched to the model and cut to the frames asked for (`path` names the file in errors).
/// "; the file's Frame# A..B" for frames first..last counted from 0, when the file numbers its
/// frames (else ""): --first-frame counts from 0, a TRC's Frame# column often from 1.
std::string fileFrameNumbers(const Trajectory& data, long first, long last);

Trajectory readToolTrajectory(const char* tool, const std::string& path, const std::string& topic);
Trajectory fitTrajectoryToModel(const char* tool, const std::string& path, const Trajectory& data,
                                const CliArgs& args, Model* model, int history = 0,
                                int* history_kept = nullptr, int* model_only = nullptr);

}  // namespace mme
