// Short-term prediction cost. Everything that does not depend on parameter values (filled
// positions, observed velocities, valid-term lists, interaction candidate pairs) is computed
// once here; evaluate() only copies a frame's state into scratch and runs the shared Engine
// (the Simulator's own integrator, so the true model costs ~0 on its simulated data).
//
// Choices where the header leaves room:
//  - Start velocity v(t) = (x(t) - x(t-1))/h for free particles; fixed particles keep the
//    model's velocity (what the Simulator does), and unknown velocities are 0.
//  - Occluded positions are replaced by the particle's last known one (else its first known,
//    else the model's): finite, and every term they could reach is dropped anyway, except for
//    a fixed particle's, which is where it always is (an anchor: the model's position).
//  - Interaction candidates are found once per frame at x(t) within a radius of: max_distance
//    when it is fixed (plus, with substeps > 1, a margin of twice the fastest observed
//    displacement in the frame, for pairs that close in during the frame); its upper bound
//    when it is free (twice its initial value when unbounded). evaluate() re-checks every
//    candidate's length at every substep against the current value, capped at that radius.
//  - Each frame's candidates are sorted by their length at x(t); evaluate() only visits the
//    prefix within the current max_distance (plus the frame's margin with substeps): the
//    others are inactive at every substep, so skipping them changes nothing but the time.
//    The search radius (the upper bound) then costs nothing per evaluation.
//  - Frames without a valid term are not integrated at all.
#include "motion_model_estimation/core/short_term_cost.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "engine.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/core/spatial_grid.h"

namespace mme {

namespace {

/// One predicted frame: where its start state, target and bookkeeping live.
struct WorkFrame {
  size_t x_off;       // into pos: x(t) (occluded samples filled)
  size_t v_off;       // into vel: v(t)
  size_t target_off;  // into pos: x(t+1)
  uint32_t valid_begin, valid_end;  // into valid: particles whose term enters the cost
  uint32_t run_begin, run_end;      // into inter_runs: this frame's interaction candidates
  double margin_m;                  // candidate slack for pairs closing in during the frame
  uint64_t fixed_evals;             // installed bonds x substeps (interactions counted apart)
  uint64_t bond_evals;              // at most (all candidates): balances parallel chunks
};

/// Per-thread scratch so evaluate() allocates nothing after its first call on a thread.
struct Workspace {
  detail::LawTable laws;
  std::vector<SpringLaw> inter_laws;
  std::vector<detail::SpringRun> runs;  // this frame's candidate prefixes
  std::vector<double> x, v, f, local;
};

/// The model's structure as the frames' bookkeeping needs it: which particles a missing one
/// affects, and which particles each interaction may join. Computed once per cost.
struct Structure {
  /// Bond graph (adjacency lists): a force reaches one bond further per substep.
  std::vector<std::vector<int>> adjacent;
  /// Members of each group that takes part in an interaction.
  std::map<std::string, std::vector<int>> group_members;
  /// Per interaction, per particle: in its group a / group b.
  std::vector<std::vector<uint8_t>> in_a, in_b;
};

/// Bond graph for the "within substeps hops" rule.
std::vector<std::vector<int>> bondGraph(const Model& model, int n) {
  std::vector<std::vector<int>> adj_lists(n);
  for (const Bond& b : model.bonds) {
    const int arity = kindArity(model.bond_types[b.type].kind);
    for (int p = 0; p < arity; ++p)
      for (int q = 0; q < arity; ++q)
        if (p != q) adj_lists[b.particles[p]].push_back(b.particles[q]);
    // A muscle's force depends on its input bonds' ends: one hop from them to its own ends.
    for (int in : b.inputs)
      for (int p = 0; p < kindArity(model.bond_types[model.bonds[in].type].kind); ++p)
        for (int q = 0; q < arity; ++q) adj_lists[model.bonds[in].particles[p]].push_back(b.particles[q]);
  }
  return adj_lists;
}

Structure modelStructure(const Model& model, int n) {
  Structure s;
  s.adjacent = bondGraph(model, n);
  // Groups involved in interactions, and for each such group its members.
  for (const Interaction& in : model.interactions) {
    s.group_members[in.group_a];
    s.group_members[in.group_b];
  }
  for (int i = 0; i < n; ++i) {
    auto it = s.group_members.find(model.particles[i].group);
    if (it != s.group_members.end()) it->second.push_back(i);
  }
  for (const Interaction& in : model.interactions) {
    s.in_a.emplace_back(n, 0);
    s.in_b.emplace_back(n, 0);
    for (int i = 0; i < n; ++i) {
      s.in_a.back()[i] = model.particles[i].group == in.group_a;
      s.in_b.back()[i] = model.particles[i].group == in.group_b;
    }
  }
  return s;
}

/// Candidate search radius of an interaction: a fixed max_distance is exact; a free one uses
/// its upper bound, or twice its initial value when unbounded (documented cap, see
/// prepareLaws).
double interactionCutoff(const BondType& type) {
  const Param& p = type.param(kMaxDistance);
  double cutoff = p.value;
  if (p.free) {
    if (p.has_max && std::isfinite(p.max)) {
      cutoff = p.max;
    } else if (p.has_value && p.value > 0.0) {
      cutoff = 2.0 * p.value;
    } else {
      throw InputError("bond type '" + type.name +
                       "': a free max_distance of an interaction needs a max bound or a "
                       "positive initial value");
    }
  }
  return cutoff;
}

/// Reused from frame to frame while the constructor lists the frames' work.
struct FrameScratch {
  std::vector<uint8_t> dropped;  // 1: term dropped (missing or reached), 2: group drop
  std::vector<int> frontier, next;
  SpatialGrid grid;
  std::vector<Eigen::Vector3d> frame_points;
  std::vector<std::pair<int, int>> found;
};

/// Free particles lacking x(t) or x(t-1), spread `substeps` hops over the bond graph (a force
/// reaches one bond further per substep), into scratch->dropped. A fixed one is where it always
/// is, seen or not (an anchor without a marker: the model's position, see
/// prepareObservations).
void markDropped(const Model& model, const Trajectory& trajectory, int n, int t, int tp,
                 int substeps, Structure& structure, FrameScratch* scratch) {
  std::vector<uint8_t>& dropped = scratch->dropped;
  std::vector<int>& frontier = scratch->frontier;
  std::fill(dropped.begin(), dropped.end(), 0);
  frontier.clear();
  for (int i = 0; i < n; ++i)
    if (!model.particles[i].fixed && (trajectory.isOccluded(t, i) || trajectory.isOccluded(tp, i))) {
      dropped[i] = 1;
      frontier.push_back(i);
    }
  // Interaction groups: a missing member makes every partner group's neighbourhood unknown.
  for (const Interaction& in : model.interactions) {
    bool miss_a = false, miss_b = false;
    // == 1: only particles actually missing (2 marks group drops of earlier interactions).
    for (int i : structure.group_members[in.group_a]) miss_a = miss_a || dropped[i] == 1;
    for (int i : structure.group_members[in.group_b]) miss_b = miss_b || dropped[i] == 1;
    std::vector<int>& drop_b = structure.group_members[in.group_b];
    std::vector<int>& drop_a = structure.group_members[in.group_a];
    if (miss_a)
      for (int i : drop_b) dropped[i] = dropped[i] ? dropped[i] : 2;
    if (miss_b)
      for (int i : drop_a) dropped[i] = dropped[i] ? dropped[i] : 2;
  }
  for (int hop = 0; hop < substeps && !frontier.empty(); ++hop) {
    scratch->next.clear();
    for (int i : frontier)
      for (int j : structure.adjacent[i])
        if (dropped[j] != 1) {
          dropped[j] = 1;
          scratch->next.push_back(j);
        }
    frontier.swap(scratch->next);
  }
}

/// Margin for pairs that close in during the frame: with substeps the simulator re-finds
/// neighbours every substep, so pairs that come within max_distance during the frame must
/// already be candidates. Twice the fastest start speed over the frame (0 without substeps).
double closingMargin(const double* v, int n, int substeps, double frame_period_s) {
  if (substeps <= 1) return 0.0;
  double vmax2 = 0.0;
  for (int i = 0; i < n; ++i)
    vmax2 = std::max(vmax2, v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] +
                                v[3 * i + 2] * v[3 * i + 2]);
  return 2.0 * std::sqrt(vmax2) * frame_period_s;
}

}  // namespace

struct ShortTermCost::Impl {
  int n = 0;
  int substeps = 1;
  double frame_period_s = 0.0;
  double dt_s = 0.0;
  detail::Engine engine;
  detail::LawTable base_laws;
  std::vector<ParamRef> free_refs;
  std::vector<int> inter_type;          // bond type of each interaction
  std::vector<double> inter_cutoff_m;   // candidate search radius of each interaction
  std::vector<uint8_t> inter_fixed_cutoff;  // 1 when the interaction's max_distance is fixed
  std::vector<double> pos;              // T x 3N filled observed positions
  std::vector<double> vel;              // frames x 3N start velocities
  std::vector<int32_t> valid;
  std::vector<detail::PairIdx> inter_pairs;
  std::vector<double> inter_d0;  // length of each candidate pair at x(t), ascending per run
  std::vector<detail::SpringRun> inter_runs;  // law = interaction index
  std::vector<WorkFrame> frames;
  uint64_t bond_evals = 0;
  uint64_t terms = 0;

  // Construction steps (defined below the struct).

  /// Everything that depends on the model alone: step sizes, laws, free parameters and the
  /// interactions' candidate radii.
  void setUp(const Model& model, int particles, double rate_hz);
  /// Lists frame t's work (t-1 -> t: start, t+1: target) when it has a valid term.
  void addFrame(const Model& model, const Trajectory& trajectory, int t, bool static_mode,
                Structure& structure, FrameScratch* scratch);
  /// Appends v(t) to vel: (x(t) - x(t-1))/h for a free particle seen at both; a fixed one
  /// keeps the model's velocity; otherwise at rest.
  void addStartVelocities(const Model& model, const Trajectory& trajectory, int t, int tp,
                          bool static_mode);
  /// Frame w's interaction candidates (pairs of the interaction's groups within its search
  /// radius at x(t), by ascending length) into inter_pairs / inter_d0 / inter_runs; the
  /// closing margin into *margin_m. Returns the number of candidates.
  uint64_t addCandidates(const WorkFrame& w, const Structure& structure, FrameScratch* scratch,
                         double* margin_m);
  /// One interaction's candidates of a frame as a run sorted by length; returns their count.
  uint64_t addRun(int32_t interaction, const std::vector<std::pair<int, int>>& found,
                  const std::vector<Eigen::Vector3d>& frame_points);

  // ----------------------------------------------------------------------------- evaluation

  void prepareLaws(const std::vector<double>& values, Workspace* ws) const {
    if (values.size() != free_refs.size()) {
      std::ostringstream err;
      err << "ShortTermCost: " << values.size() << " values for " << free_refs.size()
          << " free parameters";
      throw std::invalid_argument(err.str());
    }
    ws->laws = base_laws;  // reuses capacity: no allocation after the first call
    for (size_t k = 0; k < values.size(); ++k) ws->laws.set(free_refs[k], values[k]);
    ws->inter_laws.resize(inter_type.size());
    for (size_t k = 0; k < inter_type.size(); ++k) {
      SpringLaw law = ws->laws.spring[inter_type[k]];
      // Pairs beyond the candidate radius were never listed; capping makes that explicit so
      // the result does not depend on the candidate list's slack.
      law.max_distance = std::min(law.max_distance, inter_cutoff_m[k]);
      ws->inter_laws[k] = law;
    }
  }

  void ensureScratch(Workspace* ws) const {
    const size_t n3 = 3 * static_cast<size_t>(n);
    if (ws->runs.capacity() < inter_type.size()) ws->runs.reserve(inter_type.size());
    if (ws->x.size() < n3) {
      ws->x.resize(n3);
      ws->v.resize(n3);
      ws->f.resize(n3);
    }
  }

  /// Candidate prefixes of frame w within the current max_distance (+ margin) into ws->runs;
  /// returns the number of pair evaluations one substep does.
  uint64_t activeRuns(const WorkFrame& w, const SpringLaw* inter_laws, Workspace* ws) const {
    ws->runs.clear();
    uint64_t pairs = 0;
    for (uint32_t r = w.run_begin; r < w.run_end; ++r) {
      detail::SpringRun run = inter_runs[r];
      const double limit_m = inter_laws[run.law].max_distance + w.margin_m;
      run.end = static_cast<uint32_t>(
          std::upper_bound(inter_d0.begin() + run.begin, inter_d0.begin() + run.end, limit_m) -
          inter_d0.begin());
      if (run.end > run.begin) {
        ws->runs.push_back(run);
        pairs += run.end - run.begin;
      }
    }
    return pairs;
  }

  /// Predicts frames [f0, f1) and adds their squared errors into local (size n); with
  /// `residuals`, also writes each term's error vector at 3 x its index in `valid`.
  void run(const detail::LawTable& laws, const SpringLaw* inter_laws, size_t f0, size_t f1,
           Workspace* ws, double* local, double* residuals = nullptr) const {
    ensureScratch(ws);
    double* x = ws->x.data();
    double* v = ws->v.data();
    double* f = ws->f.data();
    const size_t bytes = 3 * static_cast<size_t>(n) * sizeof(double);
    for (size_t fr = f0; fr < f1; ++fr) {
      const WorkFrame& w = frames[fr];
      std::memcpy(x, pos.data() + w.x_off, bytes);
      std::memcpy(v, vel.data() + w.v_off, bytes);
      activeRuns(w, inter_laws, ws);
      for (int s = 0; s < substeps; ++s) {
        engine.forces(laws, x, v, f, inter_laws, inter_pairs.data(), ws->runs.data(),
                      ws->runs.size());
        engine.integrate(dt_s, f, x, v);
        engine.clamp(laws, x);
      }
      const double* target = pos.data() + w.target_off;
      for (uint32_t k = w.valid_begin; k < w.valid_end; ++k) {
        const int i3 = 3 * valid[k];
        const double dx = x[i3] - target[i3];
        const double dy = x[i3 + 1] - target[i3 + 1];
        const double dz = x[i3 + 2] - target[i3 + 2];
        local[valid[k]] += dx * dx + dy * dy + dz * dz;
        if (residuals) {
          double* r = residuals + 3 * static_cast<size_t>(k);
          r[0] = dx;
          r[1] = dy;
          r[2] = dz;
        }
      }
    }
  }

  /// evaluate() and residuals(): every frame on the calling thread, in its own workspace.
  double evaluateAll(const std::vector<double>& values, std::vector<double>* local_costs,
                     double* residuals) const {
    thread_local Workspace ws;
    prepareLaws(values, &ws);
    std::vector<double>& local = local_costs ? *local_costs : ws.local;
    local.assign(n, 0.0);
    run(ws.laws, ws.inter_laws.data(), 0, frames.size(), &ws, local.data(), residuals);
    double total = 0.0;
    for (double c : local) total += c;
    return total;
  }
};

// ------------------------------------------------------------------------------------------
// Construction: what does not depend on parameter values, computed once
// ------------------------------------------------------------------------------------------

/// Everything that depends on the model alone: step sizes, laws, free parameters and the
/// interactions' candidate radii.
void ShortTermCost::Impl::setUp(const Model& model, int particles, double rate_hz) {
  n = particles;
  substeps = model.substeps;
  frame_period_s = 1.0 / rate_hz;
  dt_s = frame_period_s / model.substeps;
  engine = detail::Engine(model);
  base_laws.load(model);
  free_refs = mme::freeParameters(model);
  for (const Interaction& in : model.interactions) {
    const BondType& type = model.bond_types[in.type];
    inter_type.push_back(in.type);
    inter_cutoff_m.push_back(interactionCutoff(type));
    inter_fixed_cutoff.push_back(!type.param(kMaxDistance).free);
  }
}

/// Lists frame t's work (t-1 -> t: start, t+1: target) when it has a valid term.
void ShortTermCost::Impl::addFrame(const Model& model, const Trajectory& trajectory, int t,
                                   bool static_mode, Structure& structure,
                                   FrameScratch* scratch) {
  const int tp = static_mode ? 0 : t - 1, tn = static_mode ? 0 : t + 1;
  markDropped(model, trajectory, n, t, tp, substeps, structure, scratch);
  WorkFrame w{};
  w.valid_begin = static_cast<uint32_t>(valid.size());
  for (int i = 0; i < n; ++i)
    if (!scratch->dropped[i] && !trajectory.isOccluded(tn, i)) valid.push_back(i);
  w.valid_end = static_cast<uint32_t>(valid.size());
  if (w.valid_end == w.valid_begin) return;  // nothing to compare: skip the frame's work

  const size_t n3 = 3 * static_cast<size_t>(n);
  w.x_off = static_cast<size_t>(t) * n3;
  w.target_off = static_cast<size_t>(tn) * n3;
  w.v_off = vel.size();
  addStartVelocities(model, trajectory, t, tp, static_mode);
  w.run_begin = static_cast<uint32_t>(inter_runs.size());
  double margin_all_m = 0.0;
  const uint64_t candidates =
      model.interactions.empty() ? 0 : addCandidates(w, structure, scratch, &margin_all_m);
  w.run_end = static_cast<uint32_t>(inter_runs.size());
  w.margin_m = substeps > 1 ? margin_all_m : 0.0;
  w.fixed_evals = static_cast<uint64_t>(substeps) *
                  (engine.numSprings() + engine.numFlexions() + engine.numMuscles() +
                   engine.numGenericBonds());
  w.bond_evals = w.fixed_evals + static_cast<uint64_t>(substeps) * candidates;
  bond_evals += w.bond_evals;
  terms += w.valid_end - w.valid_begin;
  frames.push_back(w);
}

/// Appends v(t) to vel: (x(t) - x(t-1))/h for a free particle seen at both; a fixed one
/// keeps the model's velocity; otherwise at rest.
void ShortTermCost::Impl::addStartVelocities(const Model& model, const Trajectory& trajectory,
                                             int t, int tp, bool static_mode) {
  const size_t n3 = 3 * static_cast<size_t>(n);
  const size_t v_off = vel.size();
  vel.resize(vel.size() + n3, 0.0);
  double* v = vel.data() + v_off;
  const double* xt = pos.data() + t * n3;
  const double* xp = pos.data() + tp * n3;
  for (int i = 0; i < n; ++i) {
    const Particle& p = model.particles[i];
    for (int k = 0; k < 3; ++k) {
      double vk = 0.0;  // unknown or static: at rest
      if (p.fixed) {
        vk = p.velocity_mps[k];  // what the simulator keeps for a fixed particle
      } else if (!static_mode && !trajectory.isOccluded(t, i) && !trajectory.isOccluded(tp, i)) {
        vk = (xt[3 * i + k] - xp[3 * i + k]) / frame_period_s;
      }
      v[3 * i + k] = vk;
    }
  }
}

/// Frame w's interaction candidates (pairs of the interaction's groups within its search
/// radius at x(t), by ascending length) into inter_pairs / inter_d0 / inter_runs; the
/// closing margin into *margin_m. Returns the number of candidates.
uint64_t ShortTermCost::Impl::addCandidates(const WorkFrame& w, const Structure& structure,
                                            FrameScratch* scratch, double* margin_m) {
  const double* xt = pos.data() + w.x_off;
  // A fixed max_distance gets the closing margin (a free one is searched up to its upper
  // bound, which already leaves room).
  *margin_m = closingMargin(vel.data() + w.v_off, n, substeps, frame_period_s);
  double frame_cell_m = 0.0;
  std::vector<double> radius_m(inter_type.size(), 0.0);
  for (size_t k = 0; k < inter_type.size(); ++k) {
    const double c = inter_cutoff_m[k];
    if (!(c > 0.0) || !std::isfinite(c)) continue;
    radius_m[k] = c + (inter_fixed_cutoff[k] ? *margin_m : 0.0);
    frame_cell_m = std::max(frame_cell_m, radius_m[k]);
  }
  std::vector<Eigen::Vector3d>& frame_points = scratch->frame_points;
  for (int i = 0; i < n; ++i)
    frame_points[i] = Eigen::Vector3d(xt[3 * i], xt[3 * i + 1], xt[3 * i + 2]);
  if (frame_cell_m > 0.0) scratch->grid.build(frame_points, frame_cell_m);
  uint64_t candidates = 0;
  for (size_t k = 0; k < inter_type.size(); ++k) {
    const double cutoff = radius_m[k];
    if (!(cutoff > 0.0)) continue;
    scratch->found.clear();
    scratch->grid.pairsWithin(frame_points, cutoff, structure.in_a[k], structure.in_b[k],
                              &scratch->found);
    if (scratch->found.empty()) continue;
    candidates += addRun(static_cast<int32_t>(k), scratch->found, frame_points);
  }
  return candidates;
}

/// One interaction's candidates of a frame as a run sorted by length; returns their count.
uint64_t ShortTermCost::Impl::addRun(int32_t interaction,
                                     const std::vector<std::pair<int, int>>& found,
                                     const std::vector<Eigen::Vector3d>& frame_points) {
  detail::SpringRun run{interaction, static_cast<uint32_t>(inter_pairs.size()), 0};
  std::vector<std::pair<double, std::pair<int, int>>> by_length;
  by_length.reserve(found.size());
  for (const auto& p : found)
    by_length.push_back({(frame_points[p.first] - frame_points[p.second]).norm(), p});
  std::stable_sort(by_length.begin(), by_length.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& e : by_length) {
    inter_pairs.push_back({e.second.first, e.second.second});
    inter_d0.push_back(e.first);
  }
  run.end = static_cast<uint32_t>(inter_pairs.size());
  inter_runs.push_back(run);
  return run.end - run.begin;
}

ShortTermCost::ShortTermCost(const Model& model, const Trajectory& trajectory)
    : impl_(new Impl) {
  Impl& m = *impl_;
  // Checks, the frame rate and the filled positions: shared with every cost.
  Observations obs = prepareObservations(model, trajectory);
  const int n = obs.particles;
  const int num_frames = obs.frames;
  const bool static_mode = num_frames == 1;
  m.setUp(model, n, obs.frame_rate_hz);
  m.pos = std::move(obs.positions_m);

  Structure structure = modelStructure(model, n);
  FrameScratch scratch;
  scratch.dropped.resize(n);
  scratch.frame_points.resize(n);
  const int t_first = static_mode ? 0 : 1;
  const int t_last = static_mode ? 0 : num_frames - 2;  // inclusive
  for (int t = t_first; t <= t_last; ++t)
    m.addFrame(model, trajectory, t, static_mode, structure, &scratch);
  if (m.inter_pairs.size() > static_cast<size_t>(UINT32_MAX))
    throw InputError("too many interaction candidate pairs");
}

ShortTermCost::~ShortTermCost() = default;

const std::vector<ParamRef>& ShortTermCost::freeParameters() const { return impl_->free_refs; }

double ShortTermCost::evaluate(const std::vector<double>& free_values,
                              std::vector<double>* local_costs) const {
  return impl_->evaluateAll(free_values, local_costs, nullptr);
}

double ShortTermCost::residuals(const std::vector<double>& free_values,
                               std::vector<double>* residuals) const {
  residuals->resize(residualCount());  // run() writes every entry
  return impl_->evaluateAll(free_values, nullptr, residuals->data());
}

size_t ShortTermCost::residualCount() const { return 3 * impl_->valid.size(); }

double ShortTermCost::evaluateParallel(const std::vector<double>& free_values,
                                      std::vector<double>* local_costs, int threads) const {
  const Impl& m = *impl_;
  const size_t num_chunks =
      std::min(static_cast<size_t>(std::max(threads, 1)), m.frames.size());
  if (num_chunks <= 1) return evaluate(free_values, local_costs);

  thread_local Workspace ws0;
  m.prepareLaws(free_values, &ws0);
  // Contiguous chunks of about equal work (frames differ by their interaction candidates);
  // boundaries depend only on the thread count, so the result is reproducible.
  std::vector<size_t> bounds(num_chunks + 1, m.frames.size());
  bounds[0] = 0;
  {
    uint64_t acc = 0;
    size_t c = 1;
    for (size_t fr = 0; fr < m.frames.size() && c < num_chunks; ++fr) {
      acc += m.frames[fr].bond_evals;
      while (c < num_chunks && acc * num_chunks >= m.bond_evals * c) bounds[c++] = fr + 1;
    }
    for (size_t k = 1; k <= num_chunks; ++k) bounds[k] = std::max(bounds[k], bounds[k - 1]);
  }
  // Plain references: naming the thread_local inside the lambda would reach the worker's own
  // (empty) instance.
  const detail::LawTable& laws = ws0.laws;
  const SpringLaw* inter_laws = ws0.inter_laws.data();
  std::vector<std::vector<double>> locals(num_chunks, std::vector<double>(m.n, 0.0));
  std::vector<Workspace> spaces(num_chunks - 1);
  // Sized here so nothing in a worker allocates (an exception there would terminate).
  for (Workspace& w : spaces) m.ensureScratch(&w);
  std::vector<std::thread> pool;
  pool.reserve(num_chunks - 1);
  for (size_t c = 1; c < num_chunks; ++c)
    pool.emplace_back([&m, &laws, inter_laws, &bounds, &spaces, &locals, c]() {
      m.run(laws, inter_laws, bounds[c], bounds[c + 1], &spaces[c - 1], locals[c].data());
    });
  m.run(laws, inter_laws, bounds[0], bounds[1], &ws0, locals[0].data());
  for (std::thread& th : pool) th.join();

  std::vector<double>& local = local_costs ? *local_costs : ws0.local;
  local.assign(m.n, 0.0);
  for (size_t c = 0; c < num_chunks; ++c)  // chunk order: deterministic
    for (int i = 0; i < m.n; ++i) local[i] += locals[c][i];
  double total = 0.0;
  for (double c : local) total += c;
  return total;
}

uint64_t ShortTermCost::bondEvaluationsPerCall() const { return impl_->bond_evals; }

uint64_t ShortTermCost::bondEvaluationsFor(const std::vector<double>& free_values) const {
  Workspace ws;
  impl_->prepareLaws(free_values, &ws);
  uint64_t total = 0;
  for (const WorkFrame& w : impl_->frames)
    total += w.fixed_evals +
             static_cast<uint64_t>(impl_->substeps) * impl_->activeRuns(w, ws.inter_laws.data(), &ws);
  return total;
}
uint64_t ShortTermCost::termCount() const { return impl_->terms; }
int ShortTermCost::numParticles() const { return impl_->n; }

}  // namespace mme
