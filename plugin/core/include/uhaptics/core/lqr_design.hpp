#pragma once
// LQR synthesis with integral action, as in paper 001 (eq. 4-12), engine-independent:
//   linearize -> augment with integrators of (r - q) -> ZOH discretize -> DARE -> gain.
// Set-up code: may allocate, throws uhaptics::Error on invalid input.
#include <functional>

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

/// Everything an LQR-with-integrator design produces.
struct LqrDesign {
  StateSpace plant;        // linearized continuous plant (x = (qdot, q))
  StateSpace discrete;     // augmented with the integrators and discretized (no delay states)
  StateSpace design_plant; // `discrete` augmented with the input delay: what the DARE ran on
  DareResult dare;
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
  DareOptions dare;
};

/// Full redesign: linearize + augment + discretize (+ delay states) + DARE + gain. Throws uhaptics::Error.
LqrDesign designLqrWithIntegrators(const LqrDesignRequest& request);

/// Fastest pole in rad/s of the discrete closed loop A - B K: max |ln z| / T.
double fastestPoleRadPerSecond(const MatX& A_closed_loop, double period);

}  // namespace uhaptics
