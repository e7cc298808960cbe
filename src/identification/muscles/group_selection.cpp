#include "group_selection.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mme::sensor_muscles {

namespace {

/// The groups (muscles 0..M-1, then sensors M..M+S-1) and which columns are held at 0.
class Groups {
 public:
  Groups(const System& sys, int sensors, const std::vector<int>& held_at_zero)
      : m_(sys.pattern->muscles), s_(sensors), k_(sys.pattern->per_muscle), held_(sys.unknowns(), 0) {
    for (int j : held_at_zero) held_[j] = 1;
  }

  int count() const { return m_ + s_; }
  bool isMuscle(int g) const { return g < m_; }
  /// The columns of group g not held yet.
  std::vector<int> freeColumns(int g) const {
    std::vector<int> cols;
    if (isMuscle(g)) {
      for (int c = 0; c < k_; ++c) push(g * k_ + c, &cols);
    } else {
      for (int m = 0; m < m_; ++m) {
        push(m * k_ + (g - m_), &cols);
        push(m * k_ + s_ + (g - m_), &cols);
      }
    }
    return cols;
  }
  const std::vector<char>& held() const { return held_; }
  std::vector<int> heldColumns() const {
    std::vector<int> cols;
    for (int j = 0; j < static_cast<int>(held_.size()); ++j)
      if (held_[j]) cols.push_back(j);
    return cols;
  }
  void hold(const std::vector<int>& cols) {
    for (int j : cols) held_[j] = 1;
  }
  int freeCount() const { return static_cast<int>(std::count(held_.begin(), held_.end(), 0)); }

 private:
  void push(int j, std::vector<int>* cols) const {
    if (!held_[j]) cols->push_back(j);
  }
  int m_, s_, k_;
  std::vector<char> held_;
};

/// Per group, the residual's rise if it alone were removed with every other unknown held:
/// theta_g^T A_gg theta_g - 2 theta_g . (A theta - b)_g (an upper bound of the rise after the
/// others are refitted).
std::vector<double> heldRises(const System& sys, int sensors, const Eigen::VectorXd& theta) {
  const BlockPattern& p = *sys.pattern;
  const int k = p.per_muscle, muscles = p.muscles;
  const Eigen::VectorXd gradient = sys.times(theta) - sys.atb;
  std::vector<double> rise(muscles + sensors, 0.0);
  for (int m = 0; m < muscles; ++m) {
    const Eigen::VectorXd th = theta.segment(m * k, k);
    const int slot = p.find(m, m);
    if (slot >= 0) rise[m] += th.dot(sys.blocks[slot] * th);
    rise[m] -= 2.0 * th.dot(gradient.segment(m * k, k));
    for (int s = 0; s < sensors; ++s)
      for (int c : {s, sensors + s}) rise[muscles + s] -= 2.0 * theta(m * k + c) * gradient(m * k + c);
  }
  // A sensor's quadratic term runs over every block: its two columns in both muscles.
  for (int m = 0; m < muscles; ++m)
    for (size_t j = 0; j < p.coupled_below[m].size(); ++j) {
      const int m2 = p.coupled_below[m][j];
      const Eigen::MatrixXd& b = sys.blocks[p.slot[m][j]];
      const double twice = m2 == m ? 1.0 : 2.0;
      for (int s = 0; s < sensors; ++s)
        for (int r : {s, sensors + s})
          for (int c : {s, sensors + s}) rise[muscles + s] += twice * theta(m * k + r) * b(r, c) * theta(m2 * k + c);
    }
  return rise;
}

/// The groups with free columns, by their held rise over the price of those columns, cheapest
/// first.
std::vector<int> rankedGroups(const Groups& groups, const std::vector<double>& rise, double price_per_param) {
  std::vector<int> ranked;
  std::vector<double> ratio(groups.count(), 0.0);
  for (int g = 0; g < groups.count(); ++g) {
    const size_t params = groups.freeColumns(g).size();
    if (params == 0) continue;
    ratio[g] = rise[g] / (static_cast<double>(params) * price_per_param);
    ranked.push_back(g);
  }
  std::stable_sort(ranked.begin(), ranked.end(), [&](int a, int b) { return ratio[a] < ratio[b]; });
  return ranked;
}

}  // namespace

int GroupSelection::groups_dropped() const {
  return static_cast<int>(std::count(muscle_dropped.begin(), muscle_dropped.end(), 1) +
                          std::count(sensor_dropped.begin(), sensor_dropped.end(), 1));
}

std::vector<int> droppedColumns(const GroupSelection& selection, int sensors, int per_muscle) {
  std::vector<int> cols;
  const int muscles = static_cast<int>(selection.muscle_dropped.size());
  for (int m = 0; m < muscles; ++m)
    for (int c = 0; c < per_muscle; ++c)
      if (selection.dropsMuscle(m) || (c < 2 * sensors && selection.dropsSensor(c % sensors)))
        cols.push_back(m * per_muscle + c);
  return cols;
}

GroupSelection eliminateGroups(const System& sys, double ridge, const SignConstraints& constraints,
                               int sensors, int max_solves, Eigen::VectorXd* theta, EliminationReport* report) {
  Groups groups(sys, sensors, constraints.held_at_zero);
  const double rows = static_cast<double>(std::max<size_t>(sys.rows, 2));
  double rss = residualSquares(sys, *theta);
  *report = EliminationReport{};
  report->rss_before = rss;
  report->price_per_param = rss / rows * std::log(rows);
  SignConstraints trial_constraints = constraints;
  // The batch's size adapts: doubled after a removal is kept, halved after one is refused; a
  // refused removal of the single cheapest group ends the elimination.
  size_t batch_size = 1;
  while (report->solves < max_solves) {
    const std::vector<int> ranked = rankedGroups(groups, heldRises(sys, sensors, *theta), report->price_per_param);
    if (ranked.empty()) break;
    batch_size = std::min(batch_size, ranked.size());
    Groups trial = groups;
    for (size_t j = 0; j < batch_size; ++j) trial.hold(trial.freeColumns(ranked[j]));
    const int removed = groups.freeCount() - trial.freeCount();
    trial_constraints.held_at_zero = trial.heldColumns();
    Eigen::VectorXd refit;
    ++report->solves;
    if (solveRidge(sys, ridge, trial_constraints, &refit) &&
        residualSquares(sys, refit) - rss <= removed * report->price_per_param) {
      groups = trial;
      *theta = refit;
      rss = residualSquares(sys, refit);
      batch_size *= 2;
    } else if (batch_size == 1) {
      break;
    } else {
      batch_size /= 2;
    }
  }
  report->rss_after = rss;
  GroupSelection selection;
  const int muscles = sys.pattern->muscles;
  selection.muscle_dropped.assign(muscles, 0);
  selection.sensor_dropped.assign(sensors, 0);
  // A group is dropped when none of its columns is left free (the layout's held columns count as
  // held, so a muscle is dropped only when its fitted columns are).
  for (int g = 0; g < groups.count(); ++g) {
    if (!groups.freeColumns(g).empty()) continue;
    if (groups.isMuscle(g)) selection.muscle_dropped[g] = 1;
    else selection.sensor_dropped[g - muscles] = 1;
  }
  selection.parameters = groups.freeCount();
  return selection;
}

}  // namespace mme::sensor_muscles
