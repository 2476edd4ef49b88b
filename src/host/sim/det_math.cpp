#include "host/sim/det_math.h"

#include <cmath>
#include <limits>

namespace battsim {
namespace host {
namespace sim {

namespace {
// ln 2 split so that k·kLn2Hi is exact for |k| < 2^11 (Cody–Waite reduction).
constexpr double kLn2Hi = 6.93147180369123816490e-01;
constexpr double kLn2Lo = 1.90821492927058770002e-10;
constexpr double kInvLn2 = 1.44269504088896338700e+00;
}  // namespace

double det_exp(double x) {
    if (std::isnan(x)) return x;
    if (x > 709.78) return std::numeric_limits<double>::infinity();
    if (x < -745.2) return 0.0;
    const double k = std::floor(x * kInvLn2 + 0.5);
    const double r = (x - k * kLn2Hi) - k * kLn2Lo;  // |r| <= 0.35
    // Taylor series to r^15/15!: the next term is below 1e-19 relative for |r| <= 0.35.
    double p = 1.0 / 1307674368000.0;  // 1/15!
    static const double kInvFact[] = {1.0 / 87178291200.0, 1.0 / 6227020800.0, 1.0 / 479001600.0,
                                      1.0 / 39916800.0,    1.0 / 3628800.0,    1.0 / 362880.0,
                                      1.0 / 40320.0,       1.0 / 5040.0,       1.0 / 720.0,
                                      1.0 / 120.0,         1.0 / 24.0,         1.0 / 6.0,
                                      0.5,                 1.0,                1.0};
    for (double c : kInvFact) p = p * r + c;
    return std::ldexp(p, static_cast<int>(k));
}

double det_log(double x) {
    if (std::isnan(x) || x < 0.0) return std::numeric_limits<double>::quiet_NaN();
    if (x == 0.0) return -std::numeric_limits<double>::infinity();
    if (std::isinf(x)) return x;
    int e = 0;
    double m = std::frexp(x, &e);  // x = m·2^e, m in [0.5, 1)
    if (m < 0.70710678118654752440) {
        m *= 2.0;
        --e;
    }
    // log m = 2·atanh(s), s = (m−1)/(m+1), |s| <= 0.1716: the series in s² converges fast.
    const double s = (m - 1.0) / (m + 1.0);
    const double s2 = s * s;
    double sum = 0.0;
    for (int k = 25; k >= 1; k -= 2) sum = sum * s2 + 1.0 / k;
    const double log_m = 2.0 * s * sum;
    const double de = static_cast<double>(e);
    return de * kLn2Hi + (de * kLn2Lo + log_m);
}

double round_fixed(double x, int decimals) {
    if (!std::isfinite(x)) return x;
    if (decimals < 0) decimals = 0;
    if (decimals > 15) decimals = 15;
    double scale = 1.0;
    for (int i = 0; i < decimals; ++i) scale *= 10.0;  // exact up to 1e22
    const double y = x * scale;
    if (std::fabs(y) >= 4503599627370496.0) return x;  // 2^52: already an integer
    const double r = y < 0.0 ? -std::floor(-y + 0.5) : std::floor(y + 0.5);
    const double out = r / scale;
    return out == 0.0 ? 0.0 : out;  // no "-0" in outputs
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
