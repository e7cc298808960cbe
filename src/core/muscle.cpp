#include "motion_model_estimation/core/muscle.h"

#include <cmath>
#include <cstdio>

namespace mme {

int muscleNetworkSize(int inputs, int hidden) {
  const int z = 2 * inputs;
  return hidden > 0 ? hidden * z + hidden + hidden + 1 : z + 1;
}

std::string muscleNetworkKey(int inputs, int hidden, int index) {
  const int z = 2 * inputs;
  char buf[48];
  if (hidden > 0) {
    if (index < hidden * z) {
      std::snprintf(buf, sizeof buf, "w1_%d_%d", index / z, index % z);
      return buf;
    }
    index -= hidden * z;
    if (index < hidden) {
      std::snprintf(buf, sizeof buf, "b1_%d", index);
      return buf;
    }
    index -= hidden;
    if (index < hidden) {
      std::snprintf(buf, sizeof buf, "w2_%d", index);
      return buf;
    }
    return "b2";
  }
  if (index < z) {
    std::snprintf(buf, sizeof buf, "w2_%d", index);
    return buf;
  }
  return "b2";
}

int muscleNetworkIndex(int inputs, int hidden, const std::string& key) {
  // The layouts are small (at most a few hundred names): a scan keeps one source of truth.
  const int size = muscleNetworkSize(inputs, hidden);
  for (int k = 0; k < size; ++k)
    if (muscleNetworkKey(inputs, hidden, k) == key) return k;
  return -1;
}

std::string muscleNetworkLayout(int inputs, int hidden) {
  const int z = 2 * inputs;
  const std::string zs = z > 0 ? "<0.." + std::to_string(z - 1) + ">" : "";
  if (hidden > 0) {
    const std::string hs = "<0.." + std::to_string(hidden - 1) + ">";
    return (z > 0 ? "w1_" + hs + "_" + zs + ", " : std::string()) + "b1_" + hs + ", w2_" + hs +
           ", b2";
  }
  return (z > 0 ? "w2_" + zs + ", " : std::string()) + "b2";
}

double muscleActivation(const double* network, int inputs, int hidden, double gain_n,
                        const double* z) {
  const int nz = 2 * inputs;
  double y;
  if (hidden > 0) {
    const double* w1 = network;
    const double* b1 = w1 + hidden * nz;
    const double* w2 = b1 + hidden;
    y = w2[hidden];  // b2
    for (int j = 0; j < hidden; ++j) {
      double s = b1[j];
      for (int i = 0; i < nz; ++i) s += w1[j * nz + i] * z[i];
      y += w2[j] * std::tanh(s);
    }
  } else {
    y = network[nz];  // b2
    for (int i = 0; i < nz; ++i) y += network[i] * z[i];
  }
  return gain_n * std::tanh(y);
}

}  // namespace mme
