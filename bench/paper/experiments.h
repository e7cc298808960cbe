// The experiments bench_paper runs (`--only` names in brackets), one source file each group:
// tables.cpp (fig1, table1, table2, scaling, random18), defaults.cpp (defaults, accuracy),
// online.cpp (online), structure.cpp (structure, structure_real), figure5.cpp (fig5), stages.cpp
// (stages), walker.cpp (walker_oe, walker_identify) and output_error_speed.cpp (oe_speed). Each
// writes its CSV files into Settings::out_dir.
#pragma once

#include "common.h"

namespace paper {

void figure1(const Settings& s);
void table1(const Settings& s);
void table2(const Settings& s);
void scaling(const Settings& s);
void randomObjectFiles(const Settings& s);
void defaultsExperiment(const Settings& s);
void accuracyExperiment(const Settings& s);
void onlineExperiment(const Settings& s);
void structureExperiment(const Settings& s);
void structureRealExperiment(const Settings& s);
void walkerOutputError(const Settings& s);
void walkerIdentify(const Settings& s);
void figure5(const Settings& s);
void stagesExperiment(const Settings& s);
void outputErrorSpeed(const Settings& s);

}  // namespace paper
