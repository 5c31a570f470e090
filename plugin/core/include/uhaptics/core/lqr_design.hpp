#pragma once
// LQR synthesis with integral action, as in paper 001 (eq. 4-12), engine-independent:
//   linearize -> augment with integrators of (r - q) -> ZOH discretize -> DARE -> gain.
// Set-up code: may allocate, throws uhaptics::Error on invalid input.
#include <functional>
#include <vector>

#include "uhaptics/core/dare.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// Continuous or discrete linear state-space model x' = A x + B u (+ Bref r for augmented plants).
struct StateSpace {
  MatX A;
  MatX B;
  MatX Bref;  // empty unless augmented
};

/// xdot = f(x, u) of a dynamic model, written into xdot (sized like x).
using DynamicsFunction = std::function<void(const VecX& x, const VecX& u, VecX& xdot)>;

/// Numerical linearization at (x0, u0) by central differences (what MATLAB's linear analysis tool
/// does for the paper). Step per coordinate: centralDifferenceStep(); see finite_difference.hpp.
StateSpace linearize(const DynamicsFunction& f, const VecX& x0, const VecX& u0);

/// Paper eq. 7: states (x, x_i) with x_i' = r - C x; C selects the regulated outputs.
StateSpace augmentWithIntegrators(const StateSpace& plant, const MatX& C);

/// Paper eq. 10: zero-order hold with period T via one matrix exponential of the block matrix
/// [[A, B, Bref], [0, 0, 0]] * T (Van Loan), exact for piecewise-constant inputs.
StateSpace discretizeZoh(const StateSpace& continuous, double period);

/// A discrete plant whose input reaches it `delay_samples` periods late, x+ = A x + B u_{k-D} (a
/// computation/communication delay of D whole samples), written as an undelayed plant on the state
/// (x, u_{k-1}, ..., u_{k-D}):
///   [x; u_{k-1}; ...; u_{k-D}]+ = [[A, 0 .. 0, B], [0 .. 0], [I 0 .. 0], ..., [0 .. I 0]] (...) + [0; I; 0 .. 0] u_k.
/// The reference input (Bref, if any) is internal to the controller and stays undelayed. D = 0
/// returns the plant unchanged. Generic in A, B and D; throws Error on inconsistent sizes or D < 0.
StateSpace augmentWithInputDelay(const StateSpace& discrete, int delay_samples);

/// A discrete plant whose input reaches it after a random delay d in {0, ..., max_delay} samples,
/// drawn independently every sample (x+ = A x + B u_{k-d}), on the state (x, u_{k-1}, ...,
/// u_{k-max_delay}): one mode (A_d, B_d) per delay d, z+ = A_d z + B_d u_k. Mode d = 0 feeds u_k to
/// the plant directly; mode d > 0 applies the queued u_{k-d}. Every mode shifts the queue alike.
/// Throws Error like augmentWithInputDelay; max_delay >= 1.
std::vector<StateSpace> randomInputDelayModes(const StateSpace& discrete, int max_delay);

struct RandomParameterLqrOptions {
  int max_iterations = 100000;        // Riccati value-iteration steps
  double tolerance = 1e-13;           // relative change of P per step that stops the iteration
  double max_relative_residual = 1e-9;  // accepted generalized-Riccati residual
};

struct RandomParameterLqrResult {
  MatX P;                  // value matrix of the expected cost
  MatX K;                  // optimal gain, u = -K z
  int iterations = 0;
  double relative_residual = 0.0;
  double mean_square_spectral_radius = 0.0;  // of z -> E[(A_i - B_i K) z z^T (A_i - B_i K)^T] (< 1: mean-square stable)
};

/// LQR of a linear system with i.i.d. random parameters: z+ = A_i z + B_i u with probability p_i,
/// drawn independently each sample, minimizing E sum (z^T Q z + u^T R u + 2 z^T N u). Solves the
/// generalized Riccati equation
///   P = Q + E[A^T P A] - (E[A^T P B] + N) (R + E[B^T P B])^-1 (E[B^T P A] + N^T)
/// by value iteration from P = 0 (the finite-horizon costs, nondecreasing), K = (R + E[B^T P B])^-1
/// (E[B^T P A] + N^T), then checks the residual and mean-square stability. N may be empty (no cross
/// term). Convergence is geometric at about the mean-square closed-loop radius: set-up code, not a
/// servo-period redesign (the TAU wall's figures: docs/tau.md, "Random 0-3 sample command delay").
/// Sizes: A_i n x n, B_i n x m, Q n x n, R m x m, N n x m; probabilities >= 0, summing to 1.
/// Throws Error (sizes, probabilities, no convergence, not mean-square stable). Set-up code.
RandomParameterLqrResult solveRandomParameterLqr(const std::vector<MatX>& A, const std::vector<MatX>& B,
                                                 const std::vector<double>& probabilities, const MatX& Q,
                                                 const MatX& R, const MatX& N = MatX(),
                                                 const RandomParameterLqrOptions& options = {});

/// Relative residual of the generalized Riccati equation above at P.
double randomParameterRiccatiResidual(const std::vector<MatX>& A, const std::vector<MatX>& B,
                                      const std::vector<double>& probabilities, const MatX& Q, const MatX& R,
                                      const MatX& N, const MatX& P);

/// Spectral radius of the second-moment map X -> sum p_i F_i X F_i^T of z+ = F_i z (i.i.d. modes),
/// by power iteration from X = I (the map is positive, so the iterate's growth rate converges to it).
double meanSquareSpectralRadius(const std::vector<MatX>& F, const std::vector<double>& probabilities,
                                int iterations = 5000);

/// Everything an LQR-with-integrator design produces.
struct LqrDesign {
  StateSpace plant;        // linearized continuous plant (x = (qdot, q))
  StateSpace discrete;     // augmented with the integrators and discretized (no delay states)
  StateSpace design_plant; // `discrete` augmented with the input delay: what the DARE ran on
  DareResult dare;           // fixed delay (or none)
  RandomParameterLqrResult random;  // random delay: the generalized Riccati solution (dare unused)
  MatX K;                  // full gain (inputs x design_plant states)
  MatX Kc;                 // on the plant states
  MatX Ki;                 // on the integral states
  MatX Kd;                 // on the commands in flight (u_{k-1}, ..., u_{k-D}); m x 0 without delay
  double fastest_pole_rad_s = 0.0;  // max |ln z| / T over the closed-loop eigenvalues z
};

struct LqrDesignRequest {
  DynamicsFunction dynamics;
  VecX x0;          // operating point (plant states)
  VecX u0;          // input that holds it (e.g. gravity torques)
  MatX C;           // regulated outputs (rows) for the integrators
  MatX Q;           // weight on augmented states
  MatX R;           // weight on inputs
  double period = 1e-3;
  int input_delay_samples = 0;  // D: design for x+ = A x + B u_{k-D} (delay states weighted 0)
  // true: the delay is random, d ~ U{0..D} i.i.d. each sample (randomInputDelayModes,
  // solveRandomParameterLqr); fastest_pole_rad_s is then that of the mean closed loop.
  bool random_input_delay = false;
  MatX input_rate_weight;       // W (m x m, empty: none): adds (u_k - u_{k-1})^T W (u_k - u_{k-1}); needs D >= 1
  RandomParameterLqrOptions random_options;
  DareOptions dare;
};

/// Full redesign: linearize + augment + discretize (+ delay states) + DARE + gain. Throws uhaptics::Error.
LqrDesign designLqrWithIntegrators(const LqrDesignRequest& request);

/// Fastest pole in rad/s of the discrete closed loop A - B K: max |ln z| / T (NaN when its
/// eigenvalues cannot be computed).
double fastestPoleRadPerSecond(const MatX& A_closed_loop, double period);

}  // namespace uhaptics
