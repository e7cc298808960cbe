// The muscle bond kind's controller: a small feed-forward network whose inputs are the
// elongations and elongation speeds of other bonds and whose output, times a gain, is added to
// the bond's visco-elastic tension (docs/muscles.md). Layout and naming of its parameters,
// and the activation itself.
//
// Network inputs z (2n of them for n input bonds): z_i = l_i - L_i [m] for i < n, then
// z_{n+i} = (v_b - v_a) . u_i [m/s], in the order the bond lists its inputs.
//   hidden H > 0:  h_j = tanh(b1_j + sum_i w1_j_i z_i),  y = b2 + sum_j w2_j h_j
//   hidden H = 0:  y = b2 + sum_i w2_i z_i                (no hidden layer: linear in z)
//   excitation u = gain * tanh(y)   [N]
//   activation a = u, added to the tension (a > 0 pulls the ends together); with the type's
//   activation_time_constant tau > 0, a is a state instead: da/dt = (u - a) / tau (Simulator,
//   State::activation_n; docs/muscles.md)
// Parameters in storage order: w1 (row-major, H x 2n), b1 (H), w2 (H, or 2n when H = 0), b2.
#pragma once

#include <string>

namespace mme {

constexpr int kMaxMuscleInputs = 16;  ///< input bonds per muscle (network inputs: twice that)
constexpr int kMaxMuscleHidden = 32;  ///< hidden units per muscle type

/// Number of network parameters for `inputs` input bonds and `hidden` hidden units.
int muscleNetworkSize(int inputs, int hidden);
/// Name of network parameter `index`: "w1_<j>_<i>", "b1_<j>", "w2_<j>" or "b2".
std::string muscleNetworkKey(int inputs, int hidden, int index);
/// Index of the network parameter named `key` in this layout; -1 when it is not one.
int muscleNetworkIndex(int inputs, int hidden, const std::string& key);
/// The layout's names for error messages, e.g. "w1_<0..2>_<0..3>, b1_<0..2>, w2_<0..2>, b2".
std::string muscleNetworkLayout(int inputs, int hidden);

/// The excitation gain * tanh(y) [N] (a muscle's activation when it has no activation time
/// constant) for network parameters `network` (muscleNetworkSize of them) and inputs z
/// (2 * inputs values: elongations [m], then elongation speeds [m/s]).
double muscleActivation(const double* network, int inputs, int hidden, double gain_n,
                        const double* z);

}  // namespace mme
