// Small order statistics shared by the host's reports (the score table, the batch's pack
// table, the discharge analysis).
#pragma once
#include <vector>

namespace battsim {
namespace host {

// The median (the mean of the middle two for an even count); NaN for no values.
double median(std::vector<double> v);
// A robust standard deviation: the interquartile range / 1.349, the quartiles at positions
// q·(n + 1), 1-based, interpolated (as Python's statistics.quantiles); NaN below 4 values.
double robust_spread(std::vector<double> v);

}  // namespace host
}  // namespace battsim
