// Keeps a binary log's samples in time order, and tells a corrupt time stamp from a gap.
//
// A log's rows are dropped when their time goes back before the previous sample's. On its own
// that rule lets one bad time stamp ruin a log: a flipped bit that throws one ArduPilot CURR
// row 16,891 s ahead made every later row "go back", and the replay dropped 1,383 of 2,384
// rows and reported a 16,808 s flight. So a jump forward by more than kHoldUs is held, with
// the rows that follow it (at most kMaxHeld), until the log shows which it was: rows back
// before the jump make it a corrupt time stamp, and the held rows are dropped; a log that
// goes on from the jump's time makes it a gap, and they are kept. The log's first row is held
// the same way: rows far back before it make its stamp the corrupt one. A log that ends on a
// few rows beyond a jump of more than kJumpUs ends on a corrupt stamp: they are dropped.
#pragma once

#include <cstddef>
#include <deque>
#include <functional>
#include <string>

#include "core/sample.h"

namespace battsim {
namespace host {

class TimeOrder {
public:
    // A jump forward beyond this is held, and a held gap is only delayed, never changed. Held
    // from 30 s only, a corrupt stamp 20 s ahead in log171.bin had made the 198 good rows
    // after it "go back" and be dropped, moving the capacity 14 %.
    static constexpr double kHoldUs = 1.0e6;
    // Beyond this a jump is no logging gap the shared logs show (their longest is 8.8 s, a
    // text log's GPS rows): the log's first row that far ahead of the rest, or its last rows
    // that far ahead of the rest with too few after it to show a gap, carry a corrupt stamp.
    static constexpr double kJumpUs = 30.0e6;
    // Rows after a jump beyond kJumpUs at the log's end that make it a gap, not a corrupt stamp.
    static constexpr std::size_t kMinRowsAfterEndJump = 4;
    // Rows held after a jump before it is taken as a gap: a few GPS rows' worth of CURR rows.
    static constexpr std::size_t kMaxHeld = 64;
    // Times from here on cannot be a uint64_t of microseconds, nor a real log's.
    static constexpr double kMaxTimeUs = 9.2e18;

    // kind: the note's kind ("backwards"); text: the note.
    using Drop = std::function<void(const char* kind, const std::string& text)>;

    // what: how the notes name the time ("CURR time"); noun: "row" or "sample".
    TimeOrder(std::string what, std::string noun, Drop drop)
        : what_(std::move(what)), noun_(std::move(noun)), drop_(std::move(drop)) {}

    // Offers a sample at time_us (which `sample.time_us` is set from); `where` places it in
    // the file for the notes ("byte 1268717", "line 1022").
    void offer(core::Sample sample, double time_us, const std::string& where);
    // The end of the log: rows still held followed a gap, and are kept, unless they are fewer
    // than kMinRowsAfterEndJump beyond a jump over kJumpUs.
    void finish();
    // The next sample in order, if one is ready.
    bool pop(core::Sample& out);
    // Samples accepted so far (ready or popped).
    long accepted() const { return accepted_; }

private:
    struct Row {
        core::Sample sample;
        double time_us;
        std::string where;
    };
    void accept(Row row);
    void release_held();
    void drop_backwards(double time_us, double previous_us, const std::string& where);

    std::string what_, noun_;
    Drop drop_;
    std::deque<Row> held_;
    std::deque<core::Sample> ready_;
    double last_us_ = 0.0;
    long accepted_ = 0;
};

}  // namespace host
}  // namespace battsim
