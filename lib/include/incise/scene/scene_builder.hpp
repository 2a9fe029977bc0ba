#pragma once
/// \file scene_builder.hpp
/// Builds the parts a scene names, and only those ("model only what a scene requires"): the
/// mesh, the fixed node set, the external loads, the elastic problem,
/// sweep triangles only when a tool is named (with the "augmented" solver the builder leaves
/// the cut to the run, which cuts one sweep triangle at a time; otherwise it cuts first),
/// probe node sets only when probes are named; for a `slab2d` scene the starting slab and the
/// needle insertion (needle::NeedleInsertion) with its planned updates instead. Every
/// part built is recorded with its wall time and the memory it holds; every part deliberately
/// not built is recorded with the reason, so a run summary can show both.

#include <incise/cut/cut_mesh.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/needle/insertion.hpp>
#include <incise/needle/insertion3d.hpp>
#include <incise/scene/scene_spec.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace incise::interactive {
class AugmentedCutSession;
}  // namespace incise::interactive

namespace incise::scene {

/// One constructed part and what it cost.
struct BuildStep {
  std::string what;         ///< e.g. "mesh: box 16x4x4 (1536 tets, 425 nodes)"
  double seconds = 0.0;     ///< wall time spent building it
  std::size_t bytes = 0;    ///< memory held by the part (array sizes; an estimate)
  std::int64_t flops = -1;  ///< counted floating-point operations, −1 when not counted
};

/// A probe resolved against the mesh: the nodes whose displacements it averages.
struct ResolvedProbe {
  ProbeSpec spec;
  std::vector<Index> nodes;  ///< ≥ 1 node
};

/// One planned update of a needle scene: the needle's pose and how far its tip has come.
struct NeedleUpdatePlan {
  needle::NeedlePose pose;      ///< 2D: tip on the path, direction of the segment it is on
  needle::NeedlePose3D pose3d;  ///< 3D: the same in space, with the tool's radius
  double depth = 0;             ///< distance travelled by the tip along the path from its start (m)
};

/// The constructed scene. DOF numbering: node i has DOFs 3i, 3i+1, 3i+2 (x, y, z).
struct BuiltScene {
  SceneSpec spec;
  mesh::MeshData mesh;
  std::vector<Index> fixed_nodes;  ///< sorted, unique
  VecX external_force;             ///< f_ext (N), length 3·n_points (as held by `problem`)
  /// The elastic body with fixed nodes and loads applied (thesis §2.3–2.4). Note that
  /// fem::ElasticProblem always holds a lumped-mass vector (3n doubles) because its gravity
  /// load is lumped; it is counted in the problem's memory estimate.
  std::unique_ptr<fem::ElasticProblem> problem;
  std::vector<std::array<Vec3, 3>> sweep_triangles;  ///< scalpel sweep (§3.2); empty w/o tools
  std::vector<ResolvedProbe> probes;
  /// `slab2d` scenes: the needle insertion on the starting slab (thesis §6.7; `mesh` is that
  /// slab, `problem` is null: the insertion holds its plane-stress problem) and its updates.
  std::unique_ptr<needle::NeedleInsertion> needle;
  /// 3D needle scenes (a tetrahedral mesh with a needle tool, thesis §6.9): the insertion on
  /// the starting mesh (`mesh` is that mesh, `problem` is null: the insertion holds its
  /// elastic problem).
  std::unique_ptr<needle::NeedleInsertion3D> needle3d;
  /// Needle scenes (2D or 3D): the planned updates.
  std::vector<NeedleUpdatePlan> needle_plan;
  /// True for a needle scene (2D or 3D).
  bool is_needle() const { return needle || needle3d; }
  /// dynamic_parameters() may let the Lanczos estimate multiply by K(u) assembled once
  /// (solver::LanczosOptions::assembled): the problem's assembled K·d is on, or — for a
  /// "dynamic-ss22" scene — K in node blocks fits the memory budget beside mesh and problem.
  bool lanczos_assembled = false;
  /// The estimated bytes of that assembled K when the estimate assembles its own (a
  /// "dynamic-ss22" scene without the assembled K·d; 0 otherwise): counted in the Lanczos
  /// build step's memory.
  std::uint64_t lanczos_assembled_bytes = 0;
  std::vector<BuildStep> steps;        ///< what was built, in order
  std::vector<std::string> not_built;  ///< parts skipped and why

  /// Records a built part (used by callers that add parts, e.g. the solver's problem object).
  void record(std::string what, double seconds, std::size_t bytes, std::int64_t flops = -1);
};

/// Builds `spec` (mesh, fixed nodes, loads, the elastic problem, and the optional parts). Throws
/// ParseError naming the JSON path when a region selects no node (or no boundary face for a surface
/// load) or a probe location lies outside the mesh's bounding box; when a mesh generator refuses a
/// parameter (mesh::GeneratorError, at `/mesh/<parameter>`); and when the estimated bytes of the
/// mesh arrays and the elastic problem exceed the memory budget (spec.limits, default
/// incise::default_memory_budget_bytes()), checked before a generated mesh is allocated and
/// before a read mesh gets its problem; and when the loads give ‖f_ext‖ = 0 over the free DOFs
/// (at /loads: zero forces, forces on fixed nodes only, every node fixed, or underflow). Throws the
/// mesh reader's errors for bad mesh files. A `slab2d` scene builds the right-triangle slab
/// (mesh::make_right_triangle_slab; refused at /mesh/h_start or /mesh/h_start_level when width
/// or height is no integer multiple of h_start, at /mesh when its estimate exceeds the budget),
/// checks that every fixed line holds a node of it, and builds the needle::NeedleInsertion with
/// the plan of needle_updates(); no ElasticProblem. A 3D needle scene (a tetrahedral mesh whose
/// tool is a needle) builds the mesh, turns the fixed regions into needle::FixedBox and builds
/// the needle::NeedleInsertion3D; it throws ParseError at the tool's /path when no planned tip
/// lies inside the body ("never enters the body"), and at /radius (or /h_shaft) when refining
/// to h_shaft along the part of the path inside the body needs more tetrahedra than
/// max_elements: at least ℓ_in/h_shaft (every tetrahedron meeting the path has diameter
/// ≤ h_shaft, so it covers at most h_shaft of it). Nothing is written anywhere.
BuiltScene build_scene(const SceneSpec& spec);

/// The memory budget of a scene's build (bytes): limits.memory_mb MiB when set (the scene key,
/// or incise run --memory-mb), else incise::default_memory_budget_bytes(). The one budget every
/// estimate is checked against: the mesh and its problem (build_scene) and the CHOLMOD factors
/// of the "augmented" solver (run_scene, from the symbolic analysis).
std::uint64_t memory_budget_bytes(const SceneSpec& spec);

/// Where memory_budget_bytes() came from, for refusals: "limits.memory_mb = N", or the default
/// and how to change it.
std::string memory_budget_origin(const SceneSpec& spec);

/// Nodes of `mesh` in `region`, sorted. Plane tolerance 0 means 1e-9 × bounding-box diagonal.
std::vector<Index> select_nodes(const mesh::MeshData& mesh, const Region& region);

/// The updates of a needle (ToolSpec::Kind::kNeedle): update k puts the tip at distance
/// min(k·speed·h_ref, ℓ) along the path (ℓ its length), k = 0 … ⌈ℓ/(speed·h_ref)⌉, pointing
/// along the path segment the tip is on (the next one at a joint, the last one at the end),
/// with the tool's length; `three_d`: NeedleUpdatePlan::pose3d (with the tool's radius) instead
/// of pose.
std::vector<NeedleUpdatePlan> needle_updates(const ToolSpec& tool, bool three_d = false);

/// Sweep triangles of a scalpel (thesis §3.2): for each path segment p_i → p_{i+1} the quad
/// (p_i, p_{i+1}, p_{i+1}+b, p_i+b) split into two triangles, b the blade vector.
std::vector<std::array<Vec3, 3>> sweep_triangles(const ToolSpec& tool);

/// The live tetrahedra of a cut mesh as MeshData: every node (unused ones included, so node
/// indices are those of the CutMesh), reference positions (m), cells in element-handle order,
/// with their cell tags when the cut mesh has them (cut::CutMesh::tag).
mesh::MeshData live_mesh_data(const cut::CutMesh& cut_mesh);

/// The problem an augmented cut session solves, as a matrix-free fem::ElasticProblem on
/// live_mesh_data(session.mesh()) of `material`: the nodes the session holds fixed (fixed from
/// the start, unused, or constrained) fixed, and `forces` (3 × the uncut node count, N) on the
/// uncut body's nodes. For the final residual check of a cut run and the fields of its frames.
std::unique_ptr<fem::ElasticProblem> cut_session_problem(
    const interactive::AugmentedCutSession& session, const material::Material& material,
    const Eigen::Matrix3Xd& forces);

/// The material a scene names (registry model and its parameters); throws ParameterError for an
/// unknown model or inadmissible parameters (material::Material's checks).
material::Material make_material(const MaterialSpec& spec);

/// Mean displacement (m) over the probe's nodes; u holds 3 DOFs per node.
Vec3 probe_value(const ResolvedProbe& probe, const VecX& u);

}  // namespace incise::scene
