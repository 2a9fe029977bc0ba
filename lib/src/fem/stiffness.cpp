#include <incise/core/error.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fem/stiffness.hpp>

namespace incise::fem {

bool element_stiffness(const material::Material& material, const Mat34T<double>& reference,
                       const Mat34T<double>& u, Mat12T<double>& k) {
  k.setZero();
  const TetReference ref = make_tet_reference(reference);
  if (!(ref.volume > 0)) return false;
  const material::Lame p = material.lame();
  const bool ok = material::visit_model(material.model_index(), [&](auto m) {
    return TetKernel<decltype(m), double>::tangent(p, ref.z_inv, ref.b, ref.volume, u, k);
  });
  if (!ok) {
    k.setZero();
    return false;
  }
  k = 0.5 * (k + k.transpose()).eval();
  return true;
}

Eigen::SparseMatrix<double> assemble_stiffness(const mesh::MeshData& mesh,
                                               const material::Material& material) {
  ElasticProblem problem(mesh, material);
  // u = 0 is never inverted (every reference volume is positive, checked by the constructor).
  const EvalStatus s =
      problem.assemble_tangent(VecX::Zero(problem.size()), FixedDofTreatment::kKeep);
  INCISE_CHECK(s == EvalStatus::kOk, "assemble_stiffness: the tangent at u = 0 is not finite");
  const Eigen::SparseMatrix<double>& k = problem.tangent_matrix();
  const Eigen::SparseMatrix<double> kt = k.transpose();
  return 0.5 * (k + kt);
}

}  // namespace incise::fem
