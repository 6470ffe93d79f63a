// SelectiveMesh: a selectively refined mesh kept from view to view, and its changes as geomorphs.
#include <lodkit/progressive.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <span>

#include "progressive/split_state.h"
#include "progressive/view_test.h"

namespace lodkit {
namespace {

// What splits about to be applied overwrite, set aside: their points' positions and the values of the
// wedges they change (nothing else of the state they are applied to), so that the state before can be
// swapped back in for a moment without a copy of it.
class SetAside {
 public:
  SetAside(const ProgressiveMesh& pm, const std::vector<Index>& splits, std::vector<Eigen::Vector3d>& positions,
           std::vector<double>& attributes)
      : dims_(static_cast<std::size_t>(pm.attribute_dims)), positions_(positions), attributes_(attributes) {
    for (Index j : splits) {
      const VertexSplit& split = pm.splits[static_cast<std::size_t>(j)];
      points_.push_back(split.point);
      for (Index i = 0; i < split.num_attribute_changes; ++i)
        wedges_.push_back(pm.attribute_changes[static_cast<std::size_t>(split.first_attribute_change + i)].wedge);
    }
    for (std::vector<Index>* list : {&points_, &wedges_}) {
      std::sort(list->begin(), list->end());
      list->erase(std::unique(list->begin(), list->end()), list->end());
    }
    for (Index p : points_) kept_positions_.push_back(positions_[static_cast<std::size_t>(p)]);
    for (Index w : wedges_) {
      const double* at = attributes_.data() + dims_ * static_cast<std::size_t>(w);
      kept_values_.insert(kept_values_.end(), at, at + dims_);
    }
  }

  // Exchanges what is set aside with what the state holds there.
  void swap() {
    for (std::size_t i = 0; i < points_.size(); ++i) std::swap(kept_positions_[i], positions_[static_cast<std::size_t>(points_[i])]);
    for (std::size_t i = 0; i < wedges_.size(); ++i) {
      double* kept = kept_values_.data() + dims_ * i;
      std::swap_ranges(kept, kept + dims_, attributes_.data() + dims_ * static_cast<std::size_t>(wedges_[i]));
    }
  }

 private:
  std::size_t dims_;
  std::vector<Eigen::Vector3d>& positions_;
  std::vector<double>& attributes_;
  std::vector<Index> points_, wedges_;
  std::vector<Eigen::Vector3d> kept_positions_;
  std::vector<double> kept_values_;
};

}  // namespace

SelectiveMesh::SelectiveMesh(const SelectiveRefiner& refiner) : refiner_(&refiner) {
  detail::SplitState base = detail::base_state(*refiner.pm_);
  positions_ = std::move(base.positions);
  attributes_ = std::move(base.attributes);
  corners_ = std::move(base.corners);
  applied_.assign(refiner.pm_->splits.size(), 0);
  spans_ = refiner.level_spans(applied_);
}

SelectiveMesh::Change SelectiveMesh::change_to(const std::vector<char>& wanted) const {
  // A step's few splits (skipped eight at a time where none changes).
  Change c;
  const std::size_t n = applied_.size();
  for (std::size_t j = 0; j < n; ++j) {
    if ((j & 7) == 0 && j + 8 <= n && std::memcmp(applied_.data() + j, wanted.data() + j, 8) == 0) {
      j += 7;
      continue;
    }
    if (applied_[j] != wanted[j]) (applied_[j] ? c.undo : c.redo).push_back(static_cast<Index>(j));
  }
  return c;
}

// Undone from the last: a later split left applied depends on none of these (the set stays closed), so
// each one's faces hold just what it wrote. New ones are applied in order, as refine() applies them.
void SelectiveMesh::undo(const std::vector<Index>& splits) {
  for (auto j = splits.rbegin(); j != splits.rend(); ++j) {
    detail::apply_split(*refiner_->pm_, *j, false, positions_, attributes_, corners_);
    applied_[static_cast<std::size_t>(*j)] = 0;
    spans_[static_cast<std::size_t>(refiner_->pm_->splits[static_cast<std::size_t>(*j)].point)] = refiner_->span_after(*j, false);
  }
}

void SelectiveMesh::redo(const std::vector<Index>& splits) {
  for (Index j : splits) {
    detail::apply_split(*refiner_->pm_, j, true, positions_, attributes_, corners_);
    applied_[static_cast<std::size_t>(j)] = 1;
    spans_[static_cast<std::size_t>(refiner_->pm_->splits[static_cast<std::size_t>(j)].point)] = refiner_->span_after(j, true);
  }
}

SelectiveMesh::Change SelectiveMesh::reach(const std::vector<char>& wanted, bool unfold, Index& unfolding) {
  Change c = change_to(wanted);
  undo(c.undo);
  redo(c.redo);
  unfolding = 0;
  if (!unfold) {
    fold_free_ = false;
    return c;
  }
  // A state unfolded before can fold only where this change moved points; any other, anywhere. Either
  // way the same faces fold, so the splits that unfold them are refine_for_view()'s.
  std::vector<Index> touched;
  if (fold_free_)
    for (const std::vector<Index>* splits : {&c.undo, &c.redo})
      for (Index j : *splits) refiner_->append_faces_of(j, touched);
  const std::vector<Index> more = refiner_->unfold(positions_, attributes_, corners_, applied_, spans_, fold_free_ ? &touched : nullptr);
  fold_free_ = true;
  unfolding = static_cast<Index>(more.size());
  if (more.empty()) return c;
  // Net of the splits undone and applied again to unfold.
  Change net;
  std::vector<Index> fresh;
  std::set_difference(c.undo.begin(), c.undo.end(), more.begin(), more.end(), std::back_inserter(net.undo));
  std::set_difference(more.begin(), more.end(), c.undo.begin(), c.undo.end(), std::back_inserter(fresh));
  std::merge(c.redo.begin(), c.redo.end(), fresh.begin(), fresh.end(), std::back_inserter(net.redo));
  return net;
}

SelectiveLevel SelectiveMesh::move_to(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view) {
  Index unfolding = 0;
  const Change c = reach(wanted, view && view->v.unfold, unfolding);
  SelectiveLevel out = refiner_->level_of(positions_, attributes_, corners_, applied_, view);
  out.splits_refined = static_cast<Index>(c.redo.size()), out.splits_coarsened = static_cast<Index>(c.undo.size());
  out.splits_unfolding = unfolding;
  return out;
}

SelectiveMorph SelectiveMesh::morph(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view) {
  // Through the union of both sets (closed, as both are): its connectivity, with each vertex's ancestor
  // in the set before and in the new set. Which splits unfold the new set shows once it is reached:
  // reach it, and go back.
  const ProgressiveMesh& pm = *refiner_->pm_;
  Index unfolding = 0;
  const Change c = reach(wanted, view && view->v.unfold, unfolding);
  undo(c.redo);
  redo(c.undo);
  SetAside before(pm, c.redo, positions_, attributes_);
  redo(c.redo);
  SelectiveMorph out;
  Geomorph& g = out.geomorph;
  g.fine = refiner_->mesh_of(positions_, attributes_, corners_, applied_);
  Mesh& end = g.fine.mesh;
  Mesh start;
  detail::size_level_mesh(pm, end.num_vertices(), 0, start);
  // The state before, for a moment: its values and flags back where the new splits wrote.
  before.swap();
  for (Index j : c.redo) applied_[static_cast<std::size_t>(j)] = 0;
  for (Index row = 0; row < end.num_vertices(); ++row) {
    const Index w = g.fine.vertex_wedge[static_cast<std::size_t>(row)];
    detail::put_wedge(pm, positions_, attributes_, refiner_->ancestor(w, applied_), start, row);
  }
  for (Index j : c.redo) applied_[static_cast<std::size_t>(j)] = 1;
  before.swap();
  undo(c.undo);
  for (Index row = 0; row < end.num_vertices(); ++row) {
    const Index w = g.fine.vertex_wedge[static_cast<std::size_t>(row)];
    detail::put_wedge(pm, positions_, attributes_, refiner_->ancestor(w, applied_), end, row);
  }
  out.reached = refiner_->level_of(positions_, attributes_, corners_, applied_, view);
  out.reached.splits_refined = static_cast<Index>(c.redo.size()), out.reached.splits_coarsened = static_cast<Index>(c.undo.size());
  out.reached.splits_unfolding = unfolding;
  g.fine_level = out.reached.splits_applied;
  g.coarse_level = g.fine_level - out.reached.splits_refined + out.reached.splits_coarsened;
  g.start_positions = std::move(start.positions);
  g.start_normals = std::move(start.attributes.normals);
  g.start_uvs = std::move(start.attributes.uvs);
  g.start_colours = std::move(start.attributes.colours);
  return out;
}

SelectiveChanges SelectiveMesh::step(const std::vector<char>& wanted, bool unfold) {
  // Each split, either way, writes its point's position (so every wedge of the point), the new point's
  // wedges, the values of the wedges it changes, its new faces and the faces whose corners it moves.
  const SelectiveRefiner& r = *refiner_;
  const ProgressiveMesh& pm = *r.pm_;
  Index unfolding = 0;
  const Change c = reach(wanted, unfold, unfolding);
  SelectiveChanges out;
  out.splits_refined = static_cast<Index>(c.redo.size()), out.splits_coarsened = static_cast<Index>(c.undo.size());
  out.splits_unfolding = unfolding;
  for (const std::vector<Index>* splits : {&c.undo, &c.redo})
    for (Index j : *splits) {
      const VertexSplit& split = pm.splits[static_cast<std::size_t>(j)];
      const std::size_t point = static_cast<std::size_t>(split.point);
      out.wedges.insert(out.wedges.end(), r.point_wedges_.begin() + r.point_wedge_start_[point],
                        r.point_wedges_.begin() + r.point_wedge_start_[point + 1]);
      for (Index w = split.first_wedge; w < split.first_wedge + split.num_wedges; ++w) out.wedges.push_back(w);
      for (Index i = 0; i < split.num_attribute_changes; ++i)
        out.wedges.push_back(pm.attribute_changes[static_cast<std::size_t>(split.first_attribute_change + i)].wedge);
      for (Index f = split.first_face; f < split.first_face + split.num_faces; ++f) out.faces.push_back(f);
      for (Index i = 0; i < split.num_changes; ++i)
        out.faces.push_back(pm.corner_changes[static_cast<std::size_t>(split.first_change + i)].corner / 3);
    }
  for (std::vector<Index>* list : {&out.wedges, &out.faces}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  return out;
}

bool SelectiveMesh::face_shown(Index face) const {
  const Index j = refiner_->face_split_[static_cast<std::size_t>(face)];
  return j < 0 || applied_[static_cast<std::size_t>(j)];
}

const Eigen::Vector3d& SelectiveMesh::wedge_position(Index wedge) const {
  return positions_[static_cast<std::size_t>(refiner_->pm_->wedge_point[static_cast<std::size_t>(wedge)])];
}

std::span<const double> SelectiveMesh::wedge_values(Index wedge) const {
  const std::size_t dims = static_cast<std::size_t>(refiner_->pm_->attribute_dims);
  return {attributes_.data() + dims * static_cast<std::size_t>(wedge), dims};
}

std::vector<char> SelectiveMesh::closed(std::vector<char> wanted) const {
  refiner_->check_size(wanted);
  refiner_->close(wanted);
  return wanted;
}

SelectiveLevel SelectiveMesh::go_to(std::vector<char> wanted) { return move_to(closed(std::move(wanted)), nullptr); }

SelectiveLevel SelectiveMesh::adapt(const Viewpoint& view, LevelErrorKind kind) {
  const SelectiveRefiner::ViewTest test(*refiner_, view, kind);
  return move_to(test.wanted(), &test);
}

SelectiveMorph SelectiveMesh::morph_to(std::vector<char> wanted) { return morph(closed(std::move(wanted)), nullptr); }

SelectiveChanges SelectiveMesh::step_to(std::vector<char> wanted) { return step(closed(std::move(wanted)), false); }

SelectiveChanges SelectiveMesh::step_to_view(const Viewpoint& view, LevelErrorKind kind) {
  return step(SelectiveRefiner::ViewTest(*refiner_, view, kind).wanted(), view.unfold);
}

SelectiveMorph SelectiveMesh::morph_to_view(const Viewpoint& view, LevelErrorKind kind) {
  const SelectiveRefiner::ViewTest test(*refiner_, view, kind);
  return morph(test.wanted(), &test);
}

}  // namespace lodkit
