// SelectiveMesh: a selectively refined mesh kept from view to view, and its changes as geomorphs.
#include <lodkit/progressive.h>

#include <algorithm>
#include <cstring>

#include "progressive/split_state.h"
#include "progressive/view_test.h"

namespace lodkit {

SelectiveMesh::SelectiveMesh(const SelectiveRefiner& refiner) : refiner_(&refiner) {
  detail::SplitState base = detail::base_state(*refiner.pm_);
  positions_ = std::move(base.positions);
  attributes_ = std::move(base.attributes);
  corners_ = std::move(base.corners);
  applied_.assign(refiner.pm_->splits.size(), 0);
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
  }
}

void SelectiveMesh::redo(const std::vector<Index>& splits) {
  for (Index j : splits) {
    detail::apply_split(*refiner_->pm_, j, true, positions_, attributes_, corners_);
    applied_[static_cast<std::size_t>(j)] = 1;
  }
}

SelectiveLevel SelectiveMesh::move_to(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view) {
  const Change c = change_to(wanted);
  undo(c.undo);
  redo(c.redo);
  SelectiveLevel out = refiner_->level_of(positions_, attributes_, corners_, applied_, view);
  out.splits_refined = static_cast<Index>(c.redo.size()), out.splits_coarsened = static_cast<Index>(c.undo.size());
  return out;
}

SelectiveMorph SelectiveMesh::morph(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view) {
  // Through the union of both sets (closed, as both are): its connectivity, with each vertex's ancestor
  // in the set before (read from the arrays as they were) and in the new set (once it is reached).
  const ProgressiveMesh& pm = *refiner_->pm_;
  const Change c = change_to(wanted);
  const std::vector<char> before = applied_;
  const std::vector<Eigen::Vector3d> positions_before = positions_;
  const std::vector<double> attributes_before = attributes_;
  redo(c.redo);
  SelectiveMorph out;
  Geomorph& g = out.geomorph;
  g.fine = refiner_->mesh_of(positions_, attributes_, corners_, applied_);
  undo(c.undo);
  out.reached = refiner_->level_of(positions_, attributes_, corners_, applied_, view);
  out.reached.splits_refined = static_cast<Index>(c.redo.size()), out.reached.splits_coarsened = static_cast<Index>(c.undo.size());
  g.coarse_level = static_cast<Index>(std::count(before.begin(), before.end(), 1));
  g.fine_level = out.reached.splits_applied;

  Mesh& end = g.fine.mesh;
  Mesh start;
  detail::size_level_mesh(pm, end.num_vertices(), 0, start);
  for (Index row = 0; row < end.num_vertices(); ++row) {
    const Index w = g.fine.vertex_wedge[static_cast<std::size_t>(row)];
    detail::put_wedge(pm, positions_before, attributes_before, refiner_->ancestor(w, before), start, row);
    detail::put_wedge(pm, positions_, attributes_, refiner_->ancestor(w, applied_), end, row);
  }
  g.start_positions = std::move(start.positions);
  g.start_normals = std::move(start.attributes.normals);
  g.start_uvs = std::move(start.attributes.uvs);
  g.start_colours = std::move(start.attributes.colours);
  return out;
}

SelectiveLevel SelectiveMesh::go_to(std::vector<char> wanted) {
  refiner_->check_size(wanted);
  refiner_->close(wanted);
  return move_to(wanted, nullptr);
}

SelectiveLevel SelectiveMesh::adapt(const Viewpoint& view, LevelErrorKind kind) {
  const SelectiveRefiner::ViewTest test(*refiner_, view, kind);
  return move_to(test.wanted(), &test);
}

SelectiveMorph SelectiveMesh::morph_to(std::vector<char> wanted) {
  refiner_->check_size(wanted);
  refiner_->close(wanted);
  return morph(wanted, nullptr);
}

SelectiveMorph SelectiveMesh::morph_to_view(const Viewpoint& view, LevelErrorKind kind) {
  const SelectiveRefiner::ViewTest test(*refiner_, view, kind);
  return morph(test.wanted(), &test);
}

}  // namespace lodkit
