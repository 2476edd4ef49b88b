#include "app/logger_app.h"

#include "app/display_pages.h"
#include "app/readings.h"

namespace battsim {
namespace fw {

void LoggerApp::begin(const LoggerAppConfig& config) {
    config_ = config;
    sensors_ok_ = sensors_.begin();
    display_ok_ = config.display && display_.begin();
    counter_.reset(0.0f, 0.0f);
    counting_ = false;
    lines_sent_ = 0;
    header_cells_ = 0;
    displayed_ = false;
    cells_ = config.cells_in_series >= 2 && config.cells_in_series <= kTapChannels + 1 ? config.cells_in_series : 0;
}

void LoggerApp::send_header() {
    line_.clear();
    // No tap chip: every reading would lack its cells and none would be sent, so the pack
    // is recorded alone rather than not at all, until the next hello.
    header_cells_ = sensors_.has_taps() ? cells_ : 0;
    line_.append("time_us,voltage_v,current_a,shunt_mv");
    for (int c = 1; c <= header_cells_; ++c) line_.appendf(",cell%d_v", c);
    line_.append(",consumed_mah,missed_readings");
    link_.send_data(line_.c_str(), line_.size());
    if (header_cells_ != cells_) {
        link_.send_note("no INA3221: no cell columns until the next hello");
    }
}

void LoggerApp::handle_serial() {
    for (;;) {
        const LineLink::Event e = link_.poll();
        if (e == LineLink::Event::None) return;
        if (e == LineLink::Event::Hello) {
            send_header();
        } else {
            link_.send_note("the logger takes no commands; say hello to get the header again");
        }
    }
}

void LoggerApp::send_line(float current_a, const int32_t* cells_10uv) {
    line_.clear();
    line_.append_uint(reading_.time_us);
    line_.append_char(',');
    line_.append_fixed(reading_.pack.bus_10uv, kBusDecimals);
    line_.appendf(",%.9g,", static_cast<double>(current_a));
    line_.append_fixed(reading_.pack.shunt_100nv, kShuntDecimals);
    for (int c = 0; c < header_cells_; ++c) {
        line_.append_char(',');
        line_.append_fixed(cells_10uv[c], kBusDecimals);
    }
    line_.appendf(",%.3f,", static_cast<double>(counter_.status().consumed_mah));
    line_.append_uint(readings_.counters().missed);
    link_.send_data(line_.c_str(), line_.size());
    ++lines_sent_;
}

LoggerApp::Step LoggerApp::step() {
    handle_serial();
    link_.prompt_if_due(clock_.millis());
    if (!sensors_ok_) {
        const uint32_t now_ms = clock_.millis();
        if (now_ms - last_sensor_retry_ms_ >= 1000u) {
            last_sensor_retry_ms_ = now_ms;
            sensors_ok_ = sensors_.begin();
        }
        if (!sensors_ok_) {
            clock_.sleep_us(10000);
            return Step::SensorError;
        }
    }
    const ReadingLoop::Result r = readings_.next(reading_, config_.poll_us);
    if (r == ReadingLoop::Result::Timeout) return Step::Timeout;
    if (r == ReadingLoop::Result::PackError) return Step::SensorError;

    const float voltage_v = bus_voltage_v(reading_.pack);
    const float current_a = pack_current_a(reading_.pack, config_.shunt);
    if (link_.connected()) {
        // Rectangular rule on the reading's own dt, like the monitor's counter.
        if (counting_ && reading_.time_us > last_time_us_) {
            counter_.update(current_a, voltage_v, static_cast<float>(reading_.time_us - last_time_us_) * 1.0e-6f);
        }
        counting_ = true;
        last_time_us_ = reading_.time_us;

        int32_t cells_10uv[kTapChannels + 1] = {};
        const int n = header_cells_ > 0 && reading_.taps_ok
                          ? cell_voltages_10uv(reading_.pack, reading_.taps, header_cells_, cells_10uv)
                          : 0;
        // A reading whose taps failed is not sent (the host's CSV readers take no empty
        // fields); it still counts charge, and the display shows the tap errors.
        if (n == header_cells_) send_line(current_a, cells_10uv);
    }

    const uint32_t now_ms = clock_.millis();
    if (display_ok_ && (!displayed_ || now_ms - last_display_ms_ >= config_.display_interval_ms)) {
        displayed_ = true;
        last_display_ms_ = now_ms;
        LoggerPage page;
        page.voltage_v = voltage_v;
        page.current_a = current_a;
        page.consumed_mah = counter_.status().consumed_mah;
        page.lines_sent = lines_sent_;
        page.connected = link_.connected();
        page.counters = readings_.counters();
        page.taps_missing = cells_ > 0 && !sensors_.has_taps();
        draw_logger_page(display_, page);
    }
    return Step::Reading;
}

}  // namespace fw
}  // namespace battsim
