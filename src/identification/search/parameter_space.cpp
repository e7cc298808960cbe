#include "motion_model_estimation/identification/search/parameter_space.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"

namespace mme {

namespace {

/// The catalogue's facts (bond_kind.h) for a gene's parameter; a muscle's network parameters
/// (ids from kParamCount on) are signed and linear.
bool isLengthLike(int param) {
  return param < kParamCount && paramInfo(static_cast<ParamId>(param)).length_like;
}

bool isLogSearched(int param) {
  return param < kParamCount && paramInfo(static_cast<ParamId>(param)).log_search;
}

/// Default half-width of a floor height's search range around its guess (or 0) [m].
constexpr double kFloorHeightRange_m = 1.0;

/// Default search range of a muscle's network parameter (docs/muscles.md): weights read
/// elongations of centimetres, so +-100 [1/m] (or [s/m]) reaches tanh's saturation; biases
/// beyond +-5 only saturate.
constexpr double kNetworkWeightBound = 100.0;
constexpr double kNetworkBiasBound = 5.0;

bool isNetworkBias(const Model& model, const ParamRef& ref) {
  const BondType& type = model.bond_types[ref.bond_type];
  const std::string key = muscleNetworkKey(type.network_inputs, type.network_hidden,
                                           ref.param - kParamCount);
  return key[0] == 'b';
}

/// Initial std of a clamp-length gene (ln scale) around the longest observed bond.
constexpr double kClampInitSpread = 1e-3;

/// Calls visit(length) for every observed length of a bond of spring type `type` (frames where
/// both ends are seen).
template <class Visit>
void forEachObservedLength(const Model& model, const Trajectory& trajectory, int type,
                           const Visit& visit) {
  if (!bondKindInfo(model.bond_types[type].kind).has_elongation) return;
  for (const Bond& bond : model.bonds) {
    if (bond.type != type) continue;
    const int a = bond.particles[0], b = bond.particles[1];
    for (int t = 0; t < trajectory.numFrames(); ++t)
      if (!trajectory.isOccluded(t, a) && !trajectory.isOccluded(t, b))
        visit((trajectory.position(t, b) - trajectory.position(t, a)).norm());
  }
}

/// Average observed length of the bonds of a spring type; 0 when none is seen.
double averageObservedLength(const Model& model, const Trajectory& trajectory, int type) {
  double sum = 0.0;
  long count = 0;
  forEachObservedLength(model, trajectory, type, [&](double l) { sum += l; ++count; });
  return count > 0 ? sum / count : 0.0;
}

/// Longest observed length of the bonds of a spring type; 0 when none is seen.
double maxObservedLength(const Model& model, const Trajectory& trajectory, int type) {
  double longest = 0.0;
  forEachObservedLength(model, trajectory, type, [&](double l) {
    if (std::isfinite(l)) longest = std::max(longest, l);
  });
  return longest;
}

/// Observed lengths where a threshold of bond type `type` switches: its installed bonds' lengths,
/// and for interactions of that type the distances of candidate pairs of their groups (frames
/// strided so that at most ~4 million pairs are measured). Physical metres, unsorted.
std::vector<double> thresholdLengths(const Model& model, const Trajectory& trajectory, int type) {
  std::vector<double> out;
  forEachObservedLength(model, trajectory, type, [&](double l) {
    if (std::isfinite(l)) out.push_back(l);
  });
  const int frames = trajectory.numFrames();
  for (const Interaction& in : model.interactions) {
    if (in.type != type) continue;
    std::vector<int> a, b;
    for (size_t i = 0; i < model.particles.size(); ++i) {
      if (model.particles[i].group == in.group_a) a.push_back(static_cast<int>(i));
      if (model.particles[i].group == in.group_b) b.push_back(static_cast<int>(i));
    }
    const double pairs = static_cast<double>(a.size()) * static_cast<double>(b.size());
    const int stride = std::max(1, static_cast<int>(std::ceil(pairs * frames / 4e6)));
    for (int t = 0; t < frames; t += stride)
      for (int i : a)
        for (int j : b) {
          if (i == j || trajectory.isOccluded(t, i) || trajectory.isOccluded(t, j)) continue;
          const double l = (trajectory.position(t, j) - trajectory.position(t, i)).norm();
          if (std::isfinite(l) && l > 0.0) out.push_back(l);
        }
  }
  return out;
}

}  // namespace

namespace {

/// Default physical search bounds of a parameter: scaled by what is known (the observed bond
/// lengths `observed_m` for a length, the guess for a floor height).
void defaultBounds(const Model& model, const ParamRef& ref, const Param& p, double observed_m,
                   double* lo, double* hi) {
  if (ref.bond_type < 0) {  // gravity
    *lo = -30.0; *hi = 30.0;
  } else if (ref.param == kRestAngle) {
    *lo = 0.0; *hi = M_PI;
  } else if (ref.param == kMaxElongation) {
    *lo = 1e-3; *hi = 10.0;
  } else if (ref.param == kContactDepth) {
    *lo = 1e-6; *hi = 0.1;  // a micrometre to 10 cm of penetration
  } else if (ref.param == kHeight) {
    const double guess = p.has_value ? p.value : 0.0;
    *lo = guess - kFloorHeightRange_m;
    *hi = guess + kFloorHeightRange_m;
  } else if (ref.isNetwork()) {
    *hi = isNetworkBias(model, ref) ? kNetworkBiasBound : kNetworkWeightBound;
    *lo = -*hi;
  } else if (isLengthLike(ref.param)) {
    const double scale = observed_m > 0.0 ? observed_m : (p.has_value && p.value > 0 ? p.value : 1.0);
    *lo = scale / 3.0; *hi = scale * 3.0;
  } else {
    *lo = 1e-4; *hi = 1e4;
  }
}

/// The gene's search bounds: the model's when given, else the defaults; in log space for a
/// log-scaled gene. Throws InputError on empty or infinite bounds.
void setSearchBounds(const Model& model, const Param& p, double observed_m, Gene* g) {
  // `min: 0` (non-negative) keeps a log-scaled gene with the default lower bound (a value of
  // exactly 0 is not representable, a value 1e-8 of the range is).
  const bool user_min = p.has_min && !(g->log_scale && p.min <= 0.0);
  double lo, hi;
  defaultBounds(model, g->ref, p, observed_m, &lo, &hi);
  if (user_min) lo = p.min;
  if (p.has_max) hi = p.max;
  if (g->log_scale) {
    lo = std::max(lo, 1e-12);
    if (!user_min && p.has_max && !(lo < hi)) lo = hi * 1e-8;  // min: 0 below a small max
    if (!(hi > lo)) hi = lo * 10.0;
  }
  g->user_lower = user_min;
  g->user_upper = p.has_max;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi))
    throw InputError("parameter '" + g->ref.name + "': empty or infinite search bounds");
  g->lower = g->log_scale ? std::log(lo) : lo;
  g->upper = g->log_scale ? std::log(hi) : hi;
}

/// The initial distribution (the paper): lengths around the average observed distance, others
/// log-Gaussian; an initial guess in the model file centres it.
void setInitialDistribution(const Param& p, double observed_m, Gene* g) {
  const double range = g->upper - g->lower;
  if (g->ref.param == kRestLength && observed_m > 0.0 && !p.has_value) {
    g->init_center = g->log_scale ? std::log(observed_m) : observed_m;
    g->init_spread = g->log_scale ? 0.1 : 0.1 * observed_m;
  } else if (p.has_value && (!g->log_scale || p.value > 0.0)) {
    g->init_center = g->log_scale ? std::log(p.value) : p.value;
    g->init_spread = range / 6.0;
  } else {
    g->init_center = 0.5 * (g->lower + g->upper);
    g->init_spread = range / 6.0;
  }
  g->init_center = std::min(std::max(g->init_center, g->lower), g->upper);
}

/// A threshold gene's breakpoints: the observed lengths of its type's bonds inside the bounds
/// (search coordinates), sorted, at most kMaxBreakpoints spread evenly.
std::vector<double> breakpointsOf(const Model& model, const Trajectory& trajectory, const Gene& g) {
  std::vector<double> lengths = thresholdLengths(model, trajectory, g.ref.bond_type);
  for (double& l : lengths) l = g.log_scale ? std::log(l) : l;
  lengths.erase(std::remove_if(lengths.begin(), lengths.end(),
                               [&g](double v) { return !(v > g.lower && v < g.upper); }),
                lengths.end());
  std::sort(lengths.begin(), lengths.end());
  lengths.erase(std::unique(lengths.begin(), lengths.end()), lengths.end());
  constexpr size_t kMaxBreakpoints = ParameterSpace::kMaxBreakpoints;
  if (lengths.size() > kMaxBreakpoints) {
    std::vector<double> kept(kMaxBreakpoints);
    for (size_t q = 0; q < kMaxBreakpoints; ++q)
      kept[q] = lengths[q * (lengths.size() - 1) / (kMaxBreakpoints - 1)];
    lengths.swap(kept);
  }
  return lengths;
}

/// The gene of one free parameter.
Gene makeGene(const Model& model, const Trajectory& trajectory, const ParamRef& ref) {
  const Param& p = paramOf(model, ref);
  Gene g;
  g.ref = ref;
  g.has_initial = p.has_value;
  const bool is_gravity = ref.bond_type < 0;
  g.smooth = is_gravity || (ref.param != kMinDistance && ref.param != kMaxDistance);
  g.log_scale = !is_gravity && isLogSearched(ref.param);  // positive magnitudes
  const double observed_m =
      (!is_gravity && isLengthLike(ref.param)) ? averageObservedLength(model, trajectory, ref.bond_type) : 0.0;
  setSearchBounds(model, p, observed_m, &g);
  setInitialDistribution(p, observed_m, &g);
  if (!g.smooth) g.breakpoints = breakpointsOf(model, trajectory, g);
  return g;
}

/// Provot's tau becomes a clamp length (see Gene::clamp_length). With tau as the coordinate the
/// optimum is a needle: for tau above (longest observed / L - 1) the clamp is off and the cost
/// flat, just below it the clamp shortens observed bonds; and that point moves with L.
/// `type_genes`: the genes of the gene's bond type.
void makeClampLength(const Model& model, const Trajectory& trajectory, const std::vector<int>& type_genes,
                     std::vector<Gene>* genes, size_t k) {
  Gene& g = (*genes)[k];
  const int type = g.ref.bond_type;
  const Param& rest = model.bond_types[type].params[kRestLength];
  const Param& tau = model.bond_types[type].params[kMaxElongation];
  double rest_lo, rest_hi, rest_guess;
  int rest_gene = -1;
  for (int j : type_genes)
    if ((*genes)[j].ref.param == kRestLength && (*genes)[j].log_scale) rest_gene = j;
  if (rest_gene >= 0) {
    rest_lo = std::exp((*genes)[rest_gene].lower);
    rest_hi = std::exp((*genes)[rest_gene].upper);
    rest_guess = std::exp((*genes)[rest_gene].init_center);
  } else if (rest.has_value && rest.value > 0.0 && !rest.free) {
    rest_lo = rest_hi = rest_guess = rest.value;
  } else {
    return;  // rest length free but not log-scaled: keep tau as it is
  }
  g.clamp_length = true;
  g.rest_gene = rest_gene;
  g.fixed_rest_length_m = rest_gene >= 0 ? 0.0 : rest_guess;
  g.tau_lower = std::exp(g.lower);
  g.tau_upper = std::exp(g.upper);
  g.lower = std::log((1.0 + g.tau_lower) * rest_lo);
  g.upper = std::log((1.0 + g.tau_upper) * rest_hi);
  const double longest = maxObservedLength(model, trajectory, type);
  if (tau.has_value && tau.value > 0.0) {
    g.init_center = std::log((1.0 + tau.value) * rest_guess);
    g.init_spread = (g.upper - g.lower) / 6.0;
  } else if (longest > 0.0) {
    // Like rest lengths from the average observed distance: the clamp where the longest
    // observed bond of the type is (exactly right when the clamp acted in the data).
    g.init_center = std::log(longest);
    g.init_spread = kClampInitSpread;
  }
  g.init_center = std::min(std::max(g.init_center, g.lower), g.upper);
}

/// The particles each bond type acts on (its bonds' particles; an interaction's groups); the
/// last slot, gravity's: every free particle.
std::vector<std::set<int>> sitesOfTypes(const Model& model) {
  const int num_types = static_cast<int>(model.bond_types.size());
  std::vector<std::set<int>> sites(num_types + 1);
  for (const Bond& bond : model.bonds) {
    const int arity = kindArity(model.bond_types[bond.type].kind);
    for (int k = 0; k < arity; ++k) sites[bond.type].insert(bond.particles[k]);
  }
  for (const Interaction& in : model.interactions)
    for (size_t i = 0; i < model.particles.size(); ++i)
      if (model.particles[i].group == in.group_a || model.particles[i].group == in.group_b)
        sites[in.type].insert(static_cast<int>(i));
  for (size_t i = 0; i < model.particles.size(); ++i)
    if (!model.particles[i].fixed) sites[num_types].insert(static_cast<int>(i));
  return sites;
}

}  // namespace

ParameterSpace::ParameterSpace(const Model& model, const Trajectory& trajectory) {
  const int num_types = static_cast<int>(model.bond_types.size());
  genes_of_type_.assign(num_types + 1, {});  // last slot: gravity
  sites_of_type_.assign(num_types + 1, {});
  for (const ParamRef& ref : freeParameters(model)) {
    const int slot = ref.bond_type < 0 ? num_types : ref.bond_type;
    genes_of_type_[slot].push_back(static_cast<int>(genes_.size()));
    genes_.push_back(makeGene(model, trajectory, ref));
  }
  for (size_t k = 0; k < genes_.size(); ++k) {
    const Gene& g = genes_[k];
    if (g.ref.param == kMaxElongation && g.ref.bond_type >= 0 && g.log_scale)
      makeClampLength(model, trajectory, genes_of_type_[g.ref.bond_type], &genes_, k);
  }
  const std::vector<std::set<int>> sites = sitesOfTypes(model);
  for (int t = 0; t <= num_types; ++t) {
    sites_of_type_[t].assign(sites[t].begin(), sites[t].end());
    if (!genes_of_type_[t].empty()) types_with_genes_.push_back(t);
  }
}

void ParameterSpace::setBounds(size_t k, double lower, double upper) {
  Gene& g = genes_.at(k);
  if (!(upper > lower) || !std::isfinite(lower) || !std::isfinite(upper))
    throw InputError("parameter '" + g.ref.name + "': empty or infinite search bounds");
  g.lower = lower;
  g.upper = upper;
  g.init_center = std::min(std::max(g.init_center, lower), upper);
  auto outside = [&g](double v) { return !(v > g.lower && v < g.upper); };
  g.breakpoints.erase(std::remove_if(g.breakpoints.begin(), g.breakpoints.end(), outside),
                      g.breakpoints.end());
}

int ParameterSpace::boundSide(size_t k, double gene) const {
  const Gene& g = genes_.at(k);
  constexpr double kShare = 0.01;
  const double tolerance = g.log_scale ? std::log1p(kShare) : kShare * (g.upper - g.lower);
  if (gene - g.lower <= tolerance) return -1;
  if (g.upper - gene <= tolerance) return 1;
  return 0;
}

std::vector<ParamRef> ParameterSpace::refs() const {
  std::vector<ParamRef> out;
  for (const Gene& g : genes_) out.push_back(g.ref);
  return out;
}

double ParameterSpace::restLength(const Gene& g, const std::vector<double>& physical) const {
  return g.rest_gene >= 0 ? physical[g.rest_gene] : g.fixed_rest_length_m;
}

std::vector<double> ParameterSpace::toPhysical(const std::vector<double>& genes) const {
  if (genes.size() != genes_.size())
    throw InputError("ParameterSpace::toPhysical: " + std::to_string(genes.size()) +
                     " genes, expected " + std::to_string(genes_.size()));
  std::vector<double> out(genes.size());
  for (size_t k = 0; k < genes.size(); ++k)
    out[k] = genes_[k].log_scale ? std::exp(genes[k]) : genes[k];
  for (size_t k = 0; k < genes.size(); ++k) {
    const Gene& g = genes_[k];
    if (!g.clamp_length) continue;
    // tau = clamp length / L - 1, inside tau's own bounds (a clamp shorter than the rest
    // length would be no spring).
    const double tau = out[k] / restLength(g, out) - 1.0;
    out[k] = std::isfinite(tau) ? std::min(std::max(tau, g.tau_lower), g.tau_upper) : g.tau_lower;
  }
  return out;
}

std::vector<double> ParameterSpace::toSearch(const std::vector<double>& physical) const {
  if (physical.size() != genes_.size())
    throw InputError("ParameterSpace::toSearch: " + std::to_string(physical.size()) +
                     " values, expected " + std::to_string(genes_.size()));
  std::vector<double> out(physical.size());
  for (size_t k = 0; k < physical.size(); ++k) {
    const Gene& g = genes_[k];
    const double v = g.clamp_length ? (1.0 + physical[k]) * restLength(g, physical) : physical[k];
    out[k] = g.log_scale ? std::log(v) : v;
  }
  return out;
}

double ParameterSpace::physicalSlope(size_t k, const std::vector<double>& genes) const {
  const Gene& g = genes_[k];
  if (!g.log_scale) return 1.0;
  if (!g.clamp_length) return std::exp(genes[k]);
  // tau = exp(gene) / L - 1: d tau / d gene = exp(gene) / L (0 where tau is at a bound).
  const std::vector<double> physical = toPhysical(genes);
  if (physical[k] <= g.tau_lower || physical[k] >= g.tau_upper) return 0.0;
  return 1.0 + physical[k];
}

double ParameterSpace::reflect(size_t k, double v) const {
  const double lo = genes_[k].lower, hi = genes_[k].upper, w = hi - lo;
  if (!std::isfinite(v)) return 0.5 * (lo + hi);
  if (v >= lo && v <= hi) return v;
  // Fold into [lo, hi] (mirror at the bounds, repeatedly for far jumps).
  double r = std::fmod(v - lo, 2.0 * w);
  if (r < 0) r += 2.0 * w;
  return r <= w ? lo + r : hi - (r - w);
}

}  // namespace mme
