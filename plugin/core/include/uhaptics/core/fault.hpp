#pragma once
// Why a servo-rate computation refused to produce a command. Servo code never throws: it reports a
// Fault and leaves a zero (safe) command; set-up code (loading, design) throws uhaptics::Error.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace uhaptics {

enum class Fault : std::uint8_t {
  kNone = 0,
  kNonFiniteInput,     // a sensor value, proxy or parameter given to the tick was NaN or Inf
  kNonFiniteResult,    // the computation itself produced NaN or Inf (never sent on)
  kSingular,           // a configuration where the requested quantity is undefined
  kOutOfRange,         // input outside the device's working range
  kNotConverged,       // an iterative solve hit its iteration cap above tolerance
  kInvalidParameter,   // a run-time option outside its valid range
  kStalled,            // the servo loop or the device missed its deadline
  kDeviceError,        // the device or its transport reported an error
};

constexpr const char* toString(Fault f) noexcept {
  switch (f) {
    case Fault::kNone: return "none";
    case Fault::kNonFiniteInput: return "non-finite input";
    case Fault::kNonFiniteResult: return "non-finite result";
    case Fault::kSingular: return "singular configuration";
    case Fault::kOutOfRange: return "input out of range";
    case Fault::kNotConverged: return "iterative solve did not converge";
    case Fault::kInvalidParameter: return "invalid parameter";
    case Fault::kStalled: return "servo loop stalled";
    case Fault::kDeviceError: return "device error";
  }
  return "unknown fault";
}

/// Set-up time error (bad parameter file, failed design): the message says what to fix.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace uhaptics
