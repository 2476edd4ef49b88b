// Cell differences after Piao et al. (2015), on voltages only. Per sample: z-scores of
// the cell voltages; a cell's outlier value is the sum of its absolute z-distances to
// the others; when the spread of outlier values exceeds their mean, the most and least
// outlying cells seed two clusters and every cell joins the nearer one. Cells in the
// outlier cluster add their signed outlier value (negative = below the mean) to a
// running score; the reported score is that running score over the total outlier mass.
#pragma once
#include <stdint.h>

#include "core/sample.h"

namespace battsim {
namespace core {

class PiaoCellScorer {
public:
    struct Config {
        float min_std_v = 1.0e-4f;  // below this the cells are equal: nothing to score
    };
    struct Status {
        uint8_t cell_count = 0;
        float score[kMaxCells] = {};  // −1…1
        uint32_t outlier_samples = 0; // samples in which some cell was an outlier
        int8_t worst_cell = -1;       // index of the largest |score|, −1 = none
    };

    void configure(const Config& config) {
        config_ = config;
        reset();
    }
    void reset();
    void update(const float* cell_voltage_v, int cell_count);
    const Status& status() const { return status_; }

private:
    Config config_;
    Status status_;
    float running_[kMaxCells] = {};
};

}  // namespace core
}  // namespace battsim
