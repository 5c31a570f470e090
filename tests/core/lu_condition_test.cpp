#include "uhaptics/core/lu_condition.hpp"

#include <Eigen/LU>
#include "uhaptics/core/decompositions.hpp"  // the fixed-size SVDs, compiled once
#include <catch2/catch.hpp>
#include <random>

using namespace uhaptics;

TEST_CASE("LU condition: the cheap bound is below the true rcond and rcondAbove decides like rcond()") {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  int decided_by_bound = 0, cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Mat6 A;
    for (int i = 0; i < 36; ++i) A(i) = n(rng);
    // Push a quarter of the cases towards singularity: scale one singular value down to 1e-3..1e-17.
    if (trial % 4 == 0) {
      Eigen::JacobiSVD<Mat6> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Vec6 s = svd.singularValues();
      s(5) *= std::pow(10.0, -3.0 - (trial / 4) % 15);
      A = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
    }
    const Eigen::PartialPivLU<Mat6> lu(A);
    const double exact = 1.0 / (A.cwiseAbs().colwise().sum().maxCoeff() * A.inverse().cwiseAbs().colwise().sum().maxCoeff());
    CAPTURE(trial, exact, lu.rcond());
    CHECK(rcondLowerBound(lu) <= exact * (1.0 + 1e-9));
    for (const double threshold : {1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 1e-2}) {
      ++cases;
      decided_by_bound += rcondLowerBound(lu) > 2.0 * threshold;
      CHECK(rcondAbove(lu, threshold) == (lu.rcond() > threshold));
    }
  }
  // The bound is what makes the test cheap: it must decide most well-conditioned cases itself.
  CHECK(decided_by_bound > cases / 2);
}

TEST_CASE("LU condition: singular and non-finite matrices fall back to rcond()") {
  Mat6 A = Mat6::Identity();
  A(5, 5) = 0.0;
  CHECK_FALSE(rcondAbove(Eigen::PartialPivLU<Mat6>(A), 1e-12));
  CHECK_FALSE(rcondAbove(Eigen::PartialPivLU<Mat6>(Mat6::Zero()), 1e-12));
  A(5, 5) = std::nan("");
  CHECK(rcondAbove(Eigen::PartialPivLU<Mat6>(A), 1e-12) == (Eigen::PartialPivLU<Mat6>(A).rcond() > 1e-12));
  CHECK(rcondAbove(Eigen::PartialPivLU<Mat6>(Mat6::Identity()), 1e-12));
}
