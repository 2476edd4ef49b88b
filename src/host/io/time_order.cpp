#include "host/io/time_order.h"

#include <cmath>
#include <cstdint>

#include "host/io/dataflash_ulog_util.h"

namespace battsim {
namespace host {

using logio::fixed;

void TimeOrder::offer(core::Sample sample, double time_us, const std::string& where) {
    if (!std::isfinite(time_us) || time_us < 0.0 || time_us >= kMaxTimeUs) {
        drop_("bad-time", where + ": " + what_ + " " + fixed(time_us / 1e6, 6) +
                              " s is not a time a log can hold (0 to 9.2e12 s); " + noun_ + " dropped");
        return;
    }
    Row row{sample, time_us, where};
    row.sample.time_us = static_cast<uint64_t>(std::llround(time_us));
    if (accepted_ == 0 && held_.empty()) {
        // The first row is held too: a corrupt first stamp would otherwise make every row after it go back.
        held_.push_back(std::move(row));
        return;
    }
    if (!held_.empty() && accepted_ == 0 && time_us - held_.back().time_us > kHoldUs)
        release_held();  // the log's first rows were good: this row is a jump of its own
    if (!held_.empty()) {
        if (time_us >= held_.back().time_us) {
            held_.push_back(std::move(row));
            if (held_.size() > kMaxHeld) release_held();  // the log went on: a gap
            return;
        }
        const Row& first = held_.front();
        const bool undoes_jump = accepted_ > 0 ? time_us >= last_us_ && time_us < first.time_us
                                               : first.time_us - time_us > kJumpUs;
        if (undoes_jump) {
            // Back before the jump (at or after the last sample before it), or far back before the
            // log's first row: the jump was a corrupt time stamp, and the rows that carried it go.
            const std::string jump = accepted_ > 0 ? " jumps " + fixed((first.time_us - last_us_) / 1e6, 3) +
                                                         " s ahead of the previous " + noun_ + " (" +
                                                         fixed(last_us_ / 1e6, 6) + " s)"
                                                   : " is the log's first, " + fixed((first.time_us - time_us) / 1e6, 3) +
                                                         " s ahead of the " + noun_ + "s after it";
            drop_("glitch", first.where + ": " + what_ + " " + fixed(first.time_us / 1e6, 6) + " s" + jump + ", and " +
                                where + " is back at " + fixed(time_us / 1e6, 6) + " s: a corrupt time stamp; " +
                                std::to_string(held_.size()) + " " + noun_ + (held_.size() == 1 ? "" : "s") + " dropped");
            held_.clear();
            accept(std::move(row));
            return;
        }
        // Back within the held rows, or before the last sample: this one is out of order.
        drop_backwards(time_us, accepted_ > 0 && time_us < last_us_ ? last_us_ : held_.back().time_us, where);
        return;
    }
    if (time_us < last_us_) {
        drop_backwards(time_us, last_us_, where);
        return;
    }
    if (time_us - last_us_ > kHoldUs) {
        held_.push_back(std::move(row));
        return;
    }
    accept(std::move(row));
}

void TimeOrder::drop_backwards(double time_us, double previous_us, const std::string& where) {
    drop_("backwards", where + ": " + what_ + " " + fixed(time_us / 1e6, 6) + " s goes back before the previous " +
                           noun_ + " (" + fixed(previous_us / 1e6, 6) + " s); " + noun_ + " dropped");
}

void TimeOrder::accept(Row row) {
    last_us_ = row.time_us;
    ready_.push_back(row.sample);
    ++accepted_;
}

void TimeOrder::release_held() {
    while (!held_.empty()) {
        accept(std::move(held_.front()));
        held_.pop_front();
    }
}

void TimeOrder::finish() {
    // One row far ahead at the very end (a flipped bit in the last CURR time) had been kept as
    // a gap: a 16,948 s flight with 98,710 mAh counted over it on a 5.2 Ah pack.
    if (accepted_ > 0 && !held_.empty() && held_.size() < kMinRowsAfterEndJump &&
        held_.front().time_us - last_us_ > kJumpUs) {
        const Row& first = held_.front();
        drop_("glitch", first.where + ": " + what_ + " " + fixed(first.time_us / 1e6, 6) + " s jumps " +
                            fixed((first.time_us - last_us_) / 1e6, 3) + " s ahead of the previous " + noun_ + " (" +
                            fixed(last_us_ / 1e6, 6) + " s), and the log ends within " + std::to_string(held_.size()) +
                            " " + noun_ + (held_.size() == 1 ? "" : "s") + " of it: too few to show a logging gap, so a " +
                            "corrupt time stamp; " + std::to_string(held_.size()) + " " + noun_ +
                            (held_.size() == 1 ? "" : "s") + " dropped");
        held_.clear();
        return;
    }
    release_held();
}

bool TimeOrder::pop(core::Sample& out) {
    if (ready_.empty()) return false;
    out = ready_.front();
    ready_.pop_front();
    return true;
}

}  // namespace host
}  // namespace battsim
