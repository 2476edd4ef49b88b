// Charge and energy drawn since full, per sample from that sample's current, voltage
// and dt (rectangular rule, as the firmware integrates).
#pragma once
#include "core/numeric.h"

namespace battsim {
namespace core {

class CoulombCounter {
public:
    struct Status {
        float consumed_mah = 0.0f;
        float consumed_mwh = 0.0f;
    };

    void reset(float consumed_mah, float consumed_mwh) {
        mah_.reset(consumed_mah);
        mwh_.reset(consumed_mwh);
    }
    void update(float current_a, float voltage_v, float dt_s) {
        const float step_mah = current_a * dt_s * (1000.0f / 3600.0f);
        mah_.add(step_mah);
        mwh_.add(step_mah * voltage_v);
    }
    Status status() const { return Status{mah_.value(), mwh_.value()}; }

private:
    CompensatedSum mah_;
    CompensatedSum mwh_;
};

}  // namespace core
}  // namespace battsim
