#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/fem/stiffness.hpp>
#include <incise/interactive/augmented_cut_session.hpp>

#include <algorithm>

namespace incise::interactive {

const char* to_string(CutSolveStatus status) {
  switch (status) {
    case CutSolveStatus::kOk: return "ok";
    case CutSolveStatus::kFreeComponent: return "free component (singular stiffness)";
    case CutSolveStatus::kInvertedElement: return "element inverted in the reference configuration";
    case CutSolveStatus::kSolverFailed: return "augmented solve failed";
  }
  return "unknown";
}

AugmentedCutSession::AugmentedCutSession(const mesh::MeshData& mesh,
                                         const material::Material& material,
                                         const std::vector<Index>& fixed_nodes,
                                         const Eigen::Matrix3Xd& node_forces,
                                         AugmentedCutOptions options)
    : material_(material), options_(std::move(options)), policy_(options_.refactorization_mode) {
  INCISE_CHECK_PARAM(material_.name() == "linear",
                     "AugmentedCutSession needs the \"linear\" material (the augmented solver "
                     "solves the linear static problem K a = f), got \"" +
                         material_.name() + "\"");
  INCISE_CHECK_PARAM(
      options_.refactor_at_m >= 0,
      "AugmentedCutOptions::refactor_at_m must be >= 0 (0 = the automatic policy, or none)");
  mesh_ = std::make_unique<cut::CutMesh>(mesh);
  const Index n = mesh_->num_nodes();
  INCISE_CHECK_PARAM(node_forces.cols() == n, "node_forces needs one column per mesh node");
  INCISE_CHECK_PARAM(node_forces.allFinite(), "node_forces must be finite");
  initially_fixed_.assign(static_cast<size_t>(n), 0);
  for (Index v : fixed_nodes) {
    INCISE_CHECK_PARAM(v >= 0 && v < n, "fixed node index out of range");
    initially_fixed_[static_cast<size_t>(v)] = 1;
    mesh_->set_fixed(v, true);
  }
  cutter_ = std::make_unique<cut::Cutter>(*mesh_, options_.cut);
  system_ = std::make_unique<linalg::AugmentedSystem>(options_.augmented);

  node_dof_.assign(static_cast<size_t>(n), -1);
  node_force_.resize(static_cast<size_t>(n));
  int dofs = 0;
  for (Index v = 0; v < n; ++v) {
    node_force_[static_cast<size_t>(v)] = node_forces.col(v);
    if (initially_fixed_[static_cast<size_t>(v)] || mesh_->unused(v)) continue;
    node_dof_[static_cast<size_t>(v)] = dofs;
    dofs += 3;
  }
  displacement_ = Eigen::Matrix3Xd::Zero(3, n);

  // K⁰: every live element, fixed and unused nodes' DOFs left out (assembled by fem; an
  // element with non-positive reference volume has no stiffness and is counted).
  const Index cap = mesh_->element_capacity();
  records_.resize(static_cast<size_t>(cap));
  mesh::MeshData body;
  body.points = mesh_->reference_matrix();
  body.cells.resize(4, mesh_->num_elements());
  Index cells = 0;
  for (Index e = 0; e < cap; ++e) {
    if (!mesh_->alive(e)) continue;
    Record& rec = records_[static_cast<size_t>(e)];
    rec.nodes = mesh_->element(e);
    for (int a = 0; a < 4; ++a) rec.x.col(a) = mesh_->reference(rec.nodes[static_cast<size_t>(a)]);
    if (!(fem::make_tet_reference(rec.x).volume > 0)) {
      ++inverted_;
      continue;
    }
    for (int a = 0; a < 4; ++a) body.cells(a, cells) = rec.nodes[static_cast<size_t>(a)];
    ++cells;
  }
  body.cells.conservativeResize(4, cells);
  std::vector<bool> no_dof(static_cast<size_t>(3 * n));
  for (Index v = 0; v < n; ++v)
    for (int i = 0; i < 3; ++i)
      no_dof[static_cast<size_t>(3 * v + i)] = node_dof_[static_cast<size_t>(v)] < 0;
  const linalg::SparseMatrix k0 =
      linalg::remove_fixed_dofs(fem::assemble_stiffness(body, material_), no_dof).matrix;
  INCISE_ASSERT(k0.rows() == dofs, "K0 rows are the DOFs in node order");
  if (dofs > 0 && k0.diagonal().mean() > 0) constraint_spring_ = k0.diagonal().mean();
  const double cpu0 = thread_cpu_seconds();
  const Timer timer;
  const linalg::FactorStatus fs = system_->initialize(k0);
  if (fs != linalg::FactorStatus::kOk) {
    // Every status but kOk, CHOLMOD warnings included (kTinyPivot: a factor of a perturbed K⁰).
    initial_.status = CutSolveStatus::kSolverFailed;
    initial_.message = std::string("the factorization of the initial stiffness matrix failed (") +
                       linalg::to_string(fs) + ": " + system_->factorization_message() + ")";
    if (fs == linalg::FactorStatus::kNotPositiveDefinite)
      initial_.message +=
          ": fix enough nodes (at least three non-collinear ones per connected component)";
    initial_.solve.status = linalg::AugmentedStatus::kNoFactor;
    initial_.solve.message = initial_.message;
  } else {
    solve_into(initial_);
  }
  initial_.seconds_solve = timer.seconds();
  initial_.cpu_seconds_update = thread_cpu_seconds() - cpu0;
}

AugmentedCutSession::~AugmentedCutSession() = default;

std::vector<int> AugmentedCutSession::element_dofs(const cut::Tet& t) const {
  std::vector<int> d(12, -1);
  for (int a = 0; a < 4; ++a) {
    const int base = node_dof_[static_cast<size_t>(t[static_cast<size_t>(a)])];
    if (base < 0) continue;
    for (int i = 0; i < 3; ++i) d[static_cast<size_t>(3 * a + i)] = base + i;
  }
  return d;
}

void AugmentedCutSession::add_record(Index slot, double scale) {
  const Record& rec = records_[static_cast<size_t>(slot)];
  fem::Mat12T<double> ke;  // zero when the reference volume is not positive
  if (!fem::element_stiffness(material_, rec.x, fem::Mat34T<double>::Zero(), ke))
    inverted_ += scale > 0 ? 1 : -1;
  system_->add_element(element_dofs(rec.nodes), ke, scale);
}

void AugmentedCutSession::constrain(Index v, Index& counter) {
  const int d = node_dof_[static_cast<size_t>(v)];
  if (d < 0) return;
  const Vec3 u = mesh_->deformed(v) - mesh_->reference(v);
  const Eigen::Matrix<double, 1, 1> spring =
      Eigen::Matrix<double, 1, 1>::Constant(constraint_spring_);
  for (int i = 0; i < 3; ++i) {
    if (system_->is_constrained(d + i)) continue;
    system_->impose_dirichlet(d + i, u(i));
    system_->add_element({d + i}, spring);  // keeps K positive definite (file comment)
    ++counter;
  }
}

void AugmentedCutSession::assign_new_nodes(AugmentedCutStepReport& r) {
  const Index old_n = static_cast<Index>(node_dof_.size());
  const Index n = mesh_->num_nodes();
  if (n == old_n) return;
  node_dof_.resize(static_cast<size_t>(n), -1);
  initially_fixed_.resize(static_cast<size_t>(n), 0);
  node_force_.resize(static_cast<size_t>(n), Vec3::Zero());
  displacement_.conservativeResize(3, n);
  // Every node with index ≥ old_n is new (new_nodes lists them; those a later triangle of the
  // frame left unused get no DOFs).
  for (Index v = old_n; v < n; ++v) {
    displacement_.col(v) = mesh_->deformed(v) - mesh_->reference(v);
    if (mesh_->unused(v)) continue;  // e.g. a split node left unused by a refused collapse
    if (mesh_->fixed(v) && initially_fixed_[static_cast<size_t>(mesh_->origin(v))]) {
      // Copy of a node fixed from the start: fixed at zero displacement, no DOFs.
      initially_fixed_[static_cast<size_t>(v)] = 1;
      displacement_.col(v).setZero();
      continue;
    }
    node_dof_[static_cast<size_t>(v)] = system_->add_dofs(3);
    r.dofs_added += 3;
    if (mesh_->fixed(v)) constrain(v, r.constrained_fixed);
  }
}

namespace {

void append_list(std::vector<Index>& to, const std::vector<Index>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

// Merges the report of a frame's later triangle into `to` (AugmentedCutStepReport::cut).
void merge_cut_report(cut::CutStepReport& to, const cut::CutStepReport& r) {
  if (to.ok() && !r.ok()) {
    to.status = r.status;
    to.message = r.message;
  }
  to.elements_tested += r.elements_tested;
  to.edges_intersected += r.edges_intersected;
  to.faces_selected += r.faces_selected;
  to.faces_dissected += r.faces_dissected;
  to.faces_pending = r.faces_pending;
  to.halved_choices += r.halved_choices;
  to.incomplete_elements = r.incomplete_elements;
  to.nodes_snapped += r.nodes_snapped;
  to.snaps_refused += r.snaps_refused;
  to.snaps_failed += r.snaps_failed;
  to.snaps_no_projection += r.snaps_no_projection;
  to.snaps_outside_star += r.snaps_outside_star;
  to.nodes_on_sweep += r.nodes_on_sweep;
  to.snaps_fixed += r.snaps_fixed;
  to.degenerate_found += r.degenerate_found;
  to.collapses += r.collapses;
  to.incollapsible += r.incollapsible;
  to.removal_passes += r.removal_passes;
  to.free_components += r.free_components;
  to.components_fixed += r.components_fixed;
  to.full_component_check = to.full_component_check || r.full_component_check;
  append_list(to.new_nodes, r.new_nodes);
  append_list(to.moved_nodes, r.moved_nodes);
  append_list(to.changed_elements, r.changed_elements);
  append_list(to.removed_nodes, r.removed_nodes);
  append_list(to.fixed_nodes, r.fixed_nodes);
}

}  // namespace

AugmentedCutStepReport AugmentedCutSession::frame(const std::array<Vec3, 3>* triangles,
                                                  std::size_t count) {
  AugmentedCutStepReport r;
  {
    const double cpu0 = thread_cpu_seconds();
    const Timer timer;
    for (std::size_t k = 0; k < count; ++k) {
      const std::array<Vec3, 3>& t = triangles[k];
      if (k == 0) {
        r.cut = cutter_->step(t[0], t[1], t[2]);
      } else {
        merge_cut_report(r.cut, cutter_->step(t[0], t[1], t[2]));
      }
    }
    r.triangles = static_cast<int>(count);
    r.seconds_cut = timer.seconds();
    r.cpu_seconds_cut = thread_cpu_seconds() - cpu0;
  }
  const double cpu0 = thread_cpu_seconds();
  const Timer timer;
  // Translated once, after all triangles: the system is compared slot by slot with the mesh as
  // the frame left it, so a slot changed by several triangles is replaced once.
  assign_new_nodes(r);
  if (static_cast<Index>(records_.size()) < mesh_->element_capacity())
    records_.resize(static_cast<size_t>(mesh_->element_capacity()));

  // Slots whose element may differ from what the system holds: changed elements and the
  // stars of moved nodes (snapping changes reference positions, hence Kₑ). An element that
  // left a moved node's star during the frame changed its nodes, so it is a changed element.
  std::vector<Index> slots = r.cut.changed_elements;
  for (Index v : r.cut.moved_nodes) {
    for (Index e : mesh_->star(v)) slots.push_back(e);
  }
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  for (Index e : slots) {
    Record& rec = records_[static_cast<size_t>(e)];
    Record now;
    if (mesh_->alive(e)) {
      now.nodes = mesh_->element(e);
      for (int k = 0; k < 4; ++k)
        now.x.col(k) = mesh_->reference(now.nodes[static_cast<size_t>(k)]);
    }
    const bool had = rec.nodes[0] >= 0, has = now.nodes[0] >= 0;
    if (had && has && rec.nodes == now.nodes && rec.x == now.x) continue;
    if (had) {
      add_record(e, -1.0);
      ++r.elements_subtracted;
    }
    rec = now;
    if (has) {
      add_record(e, 1.0);
      ++r.elements_added;
    }
  }
  for (Index v : r.cut.fixed_nodes) constrain(v, r.constrained_fixed);
  for (Index v : r.cut.removed_nodes) {
    if (v < static_cast<Index>(node_dof_.size()) && mesh_->unused(v))
      constrain(v, r.constrained_unused);
  }
  free_components_ += r.cut.free_components - r.cut.components_fixed;
  r.seconds_update = timer.seconds();
  const Timer solve_timer;
  const bool changed = r.elements_subtracted + r.elements_added + r.dofs_added +
                           r.constrained_fixed + r.constrained_unused >
                       0;
  if (changed || !last_.solved) {
    solve_into(r);
  } else {
    // Nothing changed: the last solution stands.
    r.m_before_solve = r.m_after_solve = system_->num_replaced();
    r.status = last_.status;
    r.message = last_.message;
    r.free_components = last_.free_components;
    r.inverted_elements = last_.inverted_elements;
  }
  r.seconds_solve = solve_timer.seconds();
  r.cpu_seconds_update = thread_cpu_seconds() - cpu0;
  return r;
}

void AugmentedCutSession::set_node_force(Index v, const Vec3& force) {
  INCISE_CHECK_PARAM(v >= 0 && v < static_cast<Index>(node_force_.size()),
                     "node index out of range");
  INCISE_CHECK_PARAM(force.allFinite(), "node force must be finite");
  node_force_[static_cast<size_t>(v)] = force;
  last_.solved = false;
}

bool AugmentedCutSession::wait_for_refactorization() {
  const bool swapped = system_->wait_for_refactorization();
  if (swapped) policy_.reset();
  return swapped;
}

AugmentedCutStepReport AugmentedCutSession::solve() {
  AugmentedCutStepReport r;
  const double cpu0 = thread_cpu_seconds();
  const Timer timer;
  solve_into(r);
  r.seconds_solve = timer.seconds();
  r.cpu_seconds_update = thread_cpu_seconds() - cpu0;
  return r;
}

void AugmentedCutSession::solve_into(AugmentedCutStepReport& r) {
  r.free_components = free_components_;
  r.inverted_elements = inverted_;
  r.solved = false;
  r.m_before_solve = r.m_after_solve = system_->num_replaced();
  if (free_components_ > 0) {
    r.status = CutSolveStatus::kFreeComponent;
    r.message =
        "a component has no fixed node, so the stiffness matrix is singular: use "
        "cut::FreeComponentPolicy::kFixOnFace or fix a node of it";
  } else if (inverted_ > 0) {
    r.status = CutSolveStatus::kInvertedElement;
    r.message =
        "an element has non-positive reference volume and no stiffness: keep "
        "cut::CutOptions::refuse_inverting_snaps on";
  } else {
    const int n = system_->num_dofs();
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    for (size_t v = 0; v < node_dof_.size(); ++v) {
      if (node_dof_[v] >= 0) f.segment<3>(node_dof_[v]) = node_force_[v];
    }
    system_->set_force(f);
    Eigen::VectorXd a, reaction;
    if (options_.refactor_every_step && system_->num_replaced() > 0)
      r.refactorization_swapped = system_->refactor_now();
    // Issue 17, the synchronous choice: a finished background job is swapped in first (as the
    // solve would), then the predicted solve at the current m is compared with a refactorization
    // now (AugmentedCutOptions::synchronous_refactorization).
    bool early_swap = false, early_failed = false;
    const bool sync_on = options_.synchronous_refactorization && !options_.refactor_every_step &&
                         options_.refactor_at_m == 0 && options_.automatic_refactorization &&
                         system_->factorization_status() == linalg::FactorStatus::kOk;
    if (sync_on && system_->num_replaced() > 0) {
      if (system_->refactorization_pending()) {
        early_swap = system_->poll_refactorization();
        early_failed = !early_swap && !system_->refactorization_pending() &&
                       system_->last_refactorization_status() != linalg::FactorStatus::kOk;
      }
      const int m = system_->num_replaced();
      const int k = system_->columns_without_g();
      const double predicted = options_.synchronous_solve_cost
                                   ? options_.synchronous_solve_cost(m, k)
                                   : sync_rule_.predict(m, k);
      double refactor = 0;
      if (options_.synchronous_refactor_cost) {
        refactor = options_.synchronous_refactor_cost(*system_);
      } else if (sync_cpu_ > 0) {
        refactor = sync_cpu_;
      } else {
        const linalg::FactorizationCpu c = system_->factorization_cpu();
        refactor = c.analyze + c.factorize + c.extract;
      }
      if (m > 0 && SynchronousRefactorRule::worth_refactoring(predicted, refactor)) {
        r.synchronous_refactorization = true;
        ++sync_count_;
        if (system_->refactor_now(options_.synchronous_ordering, /*abandon_pending=*/true)) {
          r.refactorization_swapped = true;
          const linalg::FactorizationCpu c = system_->factorization_cpu();
          sync_cpu_ = c.analyze + c.factorize + c.extract;
        }
      }
    }
    r.solve = system_->solve(a, reaction);  // swaps in a finished background factor first
    if (early_failed) r.solve.refactorization_status = system_->last_refactorization_status();
    if (sync_on && r.solve.m > 0)
      sync_rule_.observe(r.solve.m, r.solve.schur_solves, r.solve.cpu_seconds_total,
                         r.solve.cpu_seconds_capacitance_factor,
                         r.solve.capacitance_refreshed || !options_.augmented.update_capacitance,
                         r.solve.cpu_seconds_new_columns);
    r.solved = true;
    // §3.6 pipeline after the solve (AugmentedCutOptions::poll_after_solve): a job that finished
    // meanwhile goes on now (to the preparation of its G, or swapped in) instead of at the next
    // solve. A job it finds failed is dropped, and no new one starts in this solve (as below).
    bool late_swap = false, late_failed = false;
    if (options_.poll_after_solve && r.solve.status != linalg::AugmentedStatus::kNoFactor &&
        system_->refactorization_pending()) {
      late_swap = system_->poll_refactorization();
      late_failed = !late_swap && !system_->refactorization_pending() &&
                    system_->last_refactorization_status() != linalg::FactorStatus::kOk;
      if (late_failed) r.solve.refactorization_status = system_->last_refactorization_status();
    }
    r.refactorization_swapped =
        r.refactorization_swapped || early_swap || r.solve.refactorization_swapped || late_swap;
    r.m_after_solve = system_->num_replaced();
    // §3.6: bound m by refactoring the current K in the background once the columns a
    // refactorization can remove (m − |𝓓|: Dirichlet DOFs stay in 𝓛; all of m with
    // AugmentedOptions::eliminate_constrained, where 𝓛 holds only the DOFs constrained since
    // the last snapshot, which the next one eliminates) reach the threshold; the next solve
    // that finds the job finished swaps it in.
    // Not in the solve that dropped a failed job (its snapshot was not positive definite): the
    // next solve makes the next attempt, so a stuck K costs one factorization every other solve.
    const bool may_start = r.solve.status != linalg::AugmentedStatus::kNoFactor &&
                           r.solve.refactorization_status == linalg::FactorStatus::kOk &&
                           system_->may_start_refactorization();
    const int removable =
        r.m_after_solve - (options_.augmented.eliminate_constrained ? 0 : r.solve.dirichlet);
    if (options_.refactor_every_step) {
      // no background job: every step refactors in refactor_now() above
    } else if (options_.refactor_at_m > 0) {
      if (may_start && removable >= options_.refactor_at_m)
        r.refactorization_started = system_->start_refactorization();
    } else if (options_.automatic_refactorization &&
               r.solve.status != linalg::AugmentedStatus::kNoFactor) {
      // RefactorizationPolicy (break-even or continuous) on measured or injected costs.
      const double update =
          options_.update_cost ? options_.update_cost(r.solve) : r.solve.seconds_total;
      policy_.observe(update, r.refactorization_swapped);
      const double factorization = options_.factorization_cost
                                       ? options_.factorization_cost(*system_)
                                       : system_->factorization_seconds();
      if (may_start && removable > 0 && policy_.should_start(factorization))
        r.refactorization_started = system_->start_refactorization();
    }
    if (!r.solve.ok()) {
      r.status = CutSolveStatus::kSolverFailed;
      r.message = r.solve.brief();
    } else {
      r.status = CutSolveStatus::kOk;
      for (size_t v = 0; v < node_dof_.size(); ++v) {
        if (node_dof_[v] >= 0)
          displacement_.col(static_cast<Index>(v)) = a.segment<3>(node_dof_[v]);
      }
      if (options_.update_deformed) mesh_->set_deformed(mesh_->reference_matrix() + displacement_);
    }
  }
  last_.status = r.status;
  last_.message = r.message;
  last_.free_components = r.free_components;
  last_.inverted_elements = r.inverted_elements;
  last_.solved = r.status == CutSolveStatus::kOk;
}

}  // namespace incise::interactive
