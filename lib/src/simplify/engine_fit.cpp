// The cost's fit after the collapses (hoppe: hoppe_fit.cpp), held to the collapses' own limits: a face
// that the fit would move past them (face_move()) or, under inverted_faces avoid or refuse, leave facing
// against the input sends its corners back where they were, until no face does. A pass that does not
// lower the cost's measure is undone and ends the fit.
#include <chrono>

#include "simplify/collapse_engine.h"

namespace lodkit::detail {

void Engine::fit_points(SimplifyResult& result) {
  if (o_.hoppe_fit_passes <= 0 || o_.record_collapses || !o_.preserve_topology || collapses_ == 0) return;
  const auto start = std::chrono::steady_clock::now();
  std::vector<Index> faces;
  for (std::size_t f = 0; f < s_.face.size(); ++f)
    if (!s_.face_dead[f]) faces.push_back(Index(f));
  HoppeFitReport report;
  for (int pass = 0; pass < o_.hoppe_fit_passes; ++pass) {
    const std::vector<Eigen::Vector3d> before = s_.position;
    const std::optional<double> energy_before = cost_->fit(s_, pass);
    if (!energy_before) {  // (nothing moved)
      if (pass == 0) return;  // the cost has no fit
      break;
    }
    if (pass == 0) report.energy_before = report.energy_after = *energy_before;
    const Index sent_back = send_back_breaking_moves(faces, before);
    const double energy_after = cost_->fit_measure(s_);
    if (!(energy_after < *energy_before)) {
      s_.position = before;
      break;
    }
    report.passes = pass + 1;
    report.energy_after = energy_after;
    report.points_sent_back += sent_back;
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.hoppe_fit = report;
}

Index Engine::send_back_breaking_moves(const std::vector<Index>& faces, const std::vector<Eigen::Vector3d>& before) {
  // A point sent back changes the faces around it: go over them all again until none breaks a limit.
  Index sent_back = 0;
  for (bool again = true; again;) {
    again = false;
    for (Index f : faces) {
      if (!move_breaks_limits(f, before)) continue;
      for (int k = 0; k < 3; ++k)
        if (const Index p = s_.corner_point(f, k); s_.position[p] != before[p])
          s_.position[p] = before[p], ++sent_back, again = true;
    }
  }
  return sent_back;
}

bool Engine::move_breaks_limits(Index f, const std::vector<Eigen::Vector3d>& before) const {
  Eigen::Vector3d was[3], now[3];
  bool moved = false;
  for (int k = 0; k < 3; ++k) {
    const Index p = s_.corner_point(f, k);
    was[k] = before[p], now[k] = s_.position[p];
    moved |= was[k] != now[k];
  }
  if (!moved) return false;
  Eigen::Vector3d n1;
  if (face_move(f, was, now, n1) != Rejection::None) return true;
  if (check_inverted_) {
    const Eigen::Vector3d n0 = (was[1] - was[0]).cross(was[2] - was[0]);
    const Eigen::Vector3d c1 = (now[0] + now[1] + now[2]) / 3.0 + s_.origin, c0 = (was[0] + was[1] + was[2]) / 3.0 + s_.origin;
    if (faces_against_input(f, c1, n1) && !faces_against_input(f, c0, n0)) return true;
  }
  return false;
}

}  // namespace lodkit::detail
