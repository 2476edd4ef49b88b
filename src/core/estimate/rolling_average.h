// Exponential averages of a quantity over a short and a long horizon (180 s and
// 1800 s for the reference monitor). The long one is what the firmware keeps on the SD
// card between flights, so a new flight starts from the pack's usual demand.
#pragma once
#include "core/numeric.h"

namespace battsim {
namespace core {

class RollingAverage {
public:
    struct Config {
        float short_time_s = 180.0f;
        float long_time_s = 1800.0f;
        float initial_value = 0.0f;  // > 0: a remembered long-term average
    };
    struct Status {
        float short_avg = 0.0f;
        float long_avg = 0.0f;
        bool valid = false;
    };

    void configure(const Config& config) {
        config_ = config;
        status_ = Status{};
        if (config.initial_value > 0.0f) {
            status_.short_avg = config.initial_value;
            status_.long_avg = config.initial_value;
            status_.valid = true;
        }
    }
    void update(float value, float dt_s) {
        if (!status_.valid) {
            status_.short_avg = value;
            status_.long_avg = value;
            status_.valid = true;
            return;
        }
        const float a_short = config_.short_time_s > 0.0f ? clampf(dt_s / config_.short_time_s, 0.0f, 1.0f) : 1.0f;
        const float a_long = config_.long_time_s > 0.0f ? clampf(dt_s / config_.long_time_s, 0.0f, 1.0f) : 1.0f;
        status_.short_avg += a_short * (value - status_.short_avg);
        status_.long_avg += a_long * (value - status_.long_avg);
    }
    const Status& status() const { return status_; }

private:
    Config config_;
    Status status_;
};

}  // namespace core
}  // namespace battsim
