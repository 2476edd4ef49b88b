// Per-cell health for the newer estimator: each cell's resistance from short-lag
// differences (as for the pack), and a capacity deviation from how fast the cell's
// resistance-compensated voltage drifts from the others' as charge is drawn (a cell with
// less capacity runs down its OCV curve faster). A cell is named only when it is beyond
// the threshold *and* beyond three standard errors.
//
// Measurement topology matters: on the reference logger the last cell is read as
// pack − last balance tap, so it carries the main lead and connector resistance; with
// `last_cell_includes_lead` it is never compared with the others (its resistance carries the
// lead, its drift mixes the two converters' gain errors); its values are still reported.
#pragma once
#include <stdint.h>

#include "core/sample.h"

namespace battsim {
namespace core {

class CellAnalyzer {
public:
    struct Config {
        float lag_s = 0.13f;
        float min_step_a = 2.0f;
        float min_excitation_a2 = 20000.0f;  // ~20 s of racing throttle
        float min_pairs = 300.0f;
        // Floor on a cell's dOCV/dSOC: on flat stretches of the curve the conversion from
        // voltage drift to capacity would amplify noise without bound.
        float min_cell_ocv_slope_v = 0.4f;
        float resistance_ratio = 1.10f;     // name a cell above this × the others' median
        float capacity_deficit = 0.10f;     // name a cell this much below the others
        float min_charge_ah = 0.1f;         // charge drawn before capacity is judged
        float significance_sigmas = 3.0f;
        bool last_cell_includes_lead = true;
    };
    enum Finding : uint8_t { kNone = 0, kHighResistance = 1, kLowCapacity = 2 };
    struct Status {
        uint8_t cell_count = 0;
        float resistance_ohm[kMaxCells] = {};
        float capacity_deficit[kMaxCells] = {};  // fraction below the others (+ = weaker)
        int8_t flagged_cell = -1;                // 0-based, −1 = none
        uint8_t finding = kNone;
    };

    void configure(const Config& config) {
        config_ = config;
        reset();
    }
    void reset();
    // pack_ocv_slope_v_per_soc: dOCV/dSOC of the pack at the present SOC; capacity_ah: pack.
    void update(uint64_t time_us, const float* cell_v, int cells, float current_a, float charge_ah,
                float pack_ocv_slope_v_per_soc, float capacity_ah);
    void break_history() { count_ = 0; }
    const Status& status() const { return status_; }

private:
    static constexpr int kHistory = 8;
    Config config_;
    Status status_;
    uint64_t t_us_[kHistory] = {};
    float i_[kHistory] = {};
    float v_[kHistory][kMaxCells] = {};
    int head_ = 0, count_ = 0;
    // Resistance sums (shared ΔI²) and per-cell drift regression sums against charge.
    float sxx_ = 0.0f, n_r_ = 0.0f;
    float sxy_[kMaxCells] = {}, syy_[kMaxCells] = {};
    float n_ = 0.0f, sq_ = 0.0f, sqq_ = 0.0f;
    float sd_[kMaxCells] = {}, sqd_[kMaxCells] = {}, sdd_[kMaxCells] = {};
};

}  // namespace core
}  // namespace battsim
