// Per-cell resistance from the large, clean current steps: take-off, landing, the start and
// end of a burst. A hover has only two of them and never gives the short-lag differences
// (CellAnalyzer) the hundreds of pairs they need, so a cell with 60 % more resistance went
// unnamed through a whole hover. Here each step is measured between two steady windows of
// kWindow samples, one before the current moves and one once it has settled again; averaging
// a window takes the balance-tap converter's quantisation (8 mV on the INA3221) down to a
// few mV. The ratio ΔV/ΔI is the cell's resistance over the step's half second or so:
// ohmic plus the fast polarisation, which a weak cell carries in proportion too.
//
// Per step, each cell's voltage change carries the noise of the two window means: each
// window's sample variance over its length, never below noise_floor_v² (a steady cell can
// read one quantisation level throughout). Steps combine as a regression through zero.
#pragma once
#include <stdint.h>

#include "core/sample.h"

namespace battsim {
namespace core {

class CellStepResistance {
public:
    struct Config {
        float min_step_a = 4.0f;        // smaller steps are throttle noise (0 = off)
        // A window is steady when each current is within this of its mean, or this fraction
        // of the mean if more: a hovering multirotor's current wanders ±5–10 % with the wind.
        float steady_band_a = 1.0f;
        float steady_band_fraction = 0.1f;
        float noise_floor_v = 0.0025f;  // per-sample cell noise at least (8 mV LSB / √12)
        uint16_t max_wait_samples = 32;  // a current still moving after this long is no step
    };
    struct Status {
        uint16_t steps = 0;
        float resistance_ohm[kMaxCells] = {};
        float sigma_ohm[kMaxCells] = {};
    };
    static constexpr int kWindow = 8;

    void configure(const Config& config) {
        config_ = config;
        reset();
    }
    void reset();
    // Every sample with valid cell voltages, on the ground as well (a take-off's "before"
    // window is the pack at rest).
    void update(const float* cell_v, int cells, float current_a);
    const Status& status() const { return status_; }

private:
    struct Window {
        float current_a = 0.0f;
        float voltage_v[kMaxCells] = {};
        float variance_v2[kMaxCells] = {};  // of the window's mean
    };
    bool ring_steady() const;
    float band_a(float mean_a) const;
    void summarise(Window* w) const;

    Config config_;
    Status status_;
    int cells_ = 0;
    float current_a_[kWindow] = {};
    float cell_v_[kWindow][kMaxCells] = {};
    int head_ = 0, count_ = 0;
    float sum_a_ = 0.0f;  // of current_a_ while the ring is full: the departure test is O(1)
    bool moving_ = false;  // between a step's start and its settled window
    uint16_t waited_ = 0;
    Window before_;
    float sxx_ = 0.0f;
    float sxy_[kMaxCells] = {};
    float svar_[kMaxCells] = {};
};

}  // namespace core
}  // namespace battsim
