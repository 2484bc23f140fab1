// A residual that is affine in its parameter blocks, r = b + sum_i A_i x_i, with its exact
// Jacobians (dr/dx_i = A_i). The integrated gravity / accelerometer-bias residuals are of this form
// once whitened; writing the Jacobian out avoids autodiff's cost (a 12-dim Jet per operation),
// which dominated the solve.
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

namespace freeinit {

/// r = b + A_0 x_0 + A_1 x_1 + A_2 x_2 + A_3 x_3, all 3-vectors.
class AffineResidual3x4 final : public ceres::SizedCostFunction<3, 3, 3, 3, 3> {
 public:
  using Mat3 = Eigen::Matrix3d;
  AffineResidual3x4(const Eigen::Vector3d& b, const Mat3& A0, const Mat3& A1, const Mat3& A2,
                    const Mat3& A3)
      : b_(b), A_{A0, A1, A2, A3} {}

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = b_;
    for (int i = 0; i < 4; ++i) {
      r += A_[i] * Eigen::Map<const Eigen::Vector3d>(x[i]);
      if (jacobians != nullptr && jacobians[i] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[i]);
        J = A_[i];
      }
    }
    return true;
  }

 private:
  Eigen::Vector3d b_;
  Mat3 A_[4];
};

}  // namespace freeinit
