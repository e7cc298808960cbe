// The problems bench_peers runs the methods on: the speed part's scenes (paper_object,
// provot_cloth, reduced fluid_jet, cable_object) and one setting of the stability map.
#pragma once

#include <cstdint>
#include <string>

#include "problem.h"

namespace peers {

constexpr int kPaperFrames = 100;  // (a): the paper's set-up
constexpr int kMapFrames = 60;     // (b): the map's base window (paper_object)

bench::Problem paperProblem(int frames);
bench::Problem clothProblem();
/// fluid_jet reduced: frames [first, first + frames) of its simulation (the jet meets the gas).
bench::Problem fluidProblem(int first, int frames);
bench::Problem cableProblem(int cables, int frames, uint64_t seed);
bench::Problem randomProblem(int unknowns, int frames, uint64_t seed);
/// One setting of the stability map for one seed. The base is paper_object, kMapFrames frames,
/// noise-free, fully visible, the paper's initial distribution.
bench::Problem mapProblem(const std::string& axis, double value, int seed, int frames);

}  // namespace peers
