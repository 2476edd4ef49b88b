// Seeded random numbers for the simulator, implemented here so that a seed gives the same
// sequence on every platform and standard library (std::normal_distribution and friends
// are implementation-defined). Generator: xoshiro256** seeded through splitmix64.
#pragma once
#include <cstdint>

namespace battsim {
namespace host {
namespace sim {

class Rng {
public:
    explicit Rng(uint64_t seed = 0);
    // An independent stream for one purpose (profile, pack spread, sensor...), so that
    // changing how much one part draws never shifts the numbers another part sees.
    static Rng stream(uint64_t seed, uint64_t stream_id);
    // A generator with this exact xoshiro256** state (for checking against the published
    // reference sequence).
    static Rng from_state(uint64_t s0, uint64_t s1, uint64_t s2, uint64_t s3);

    uint64_t next_u64();
    double uniform();                       // [0, 1), 53 random bits
    double uniform(double lo, double hi);   // [lo, hi)
    int uniform_int(int lo, int hi);        // lo..hi inclusive
    double normal();                        // standard normal (Marsaglia polar method)
    double normal(double mean, double sd) { return mean + sd * normal(); }
    double exponential(double mean);        // mean > 0
    bool chance(double p) { return uniform() < p; }

private:
    uint64_t s_[4];
    bool has_spare_ = false;
    double spare_ = 0.0;
};

}  // namespace sim
}  // namespace host
}  // namespace battsim
