// Deterministic exp and log for the simulator. C libraries may round exp/log differently
// in the last place; these use only +, −, ×, ÷ (each correctly rounded by IEEE 754, and
// the build forbids fused multiply-add) plus exact ldexp/frexp, so every platform gets the
// same bits and a seeded simulation writes the same log everywhere.
#pragma once

namespace battsim {
namespace host {
namespace sim {

double det_exp(double x);
// x > 0; returns -inf for 0 and NaN for negative or NaN input.
double det_log(double x);

// Rounds to `decimals` places (0..15) with exact power-of-ten scaling, half away from
// zero, for short and platform-independent numbers in JSON outputs.
double round_fixed(double x, int decimals);

}  // namespace sim
}  // namespace host
}  // namespace battsim
