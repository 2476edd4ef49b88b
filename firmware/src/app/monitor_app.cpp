#include "app/monitor_app.h"

#include <stdio.h>
#include <string.h>

#include "app/averages_file.h"
#include "app/display_pages.h"
#include "app/readings.h"

namespace battsim {
namespace fw {

namespace {

constexpr const char* kLogDir = "battsim";

int series_cells_for(int cells_in_series) {
    return cells_in_series >= 2 && cells_in_series <= kTapChannels + 1 ? cells_in_series : 0;
}

bool parse_switch(const char* word, bool& out) {
    if (strcmp(word, "on") == 0) {
        out = true;
        return true;
    }
    if (strcmp(word, "off") == 0) {
        out = false;
        return true;
    }
    return false;
}

// "out WHAT HOW" → what, how (each at most 7 characters).
bool split_out_command(const char* cmd, char (&what)[8], char (&how)[8]) {
    if (strncmp(cmd, "out ", 4) != 0) return false;
    const char* p = cmd + 4;
    const char* space = strchr(p, ' ');
    if (space == nullptr || space == p || space - p >= 8) return false;
    memcpy(what, p, static_cast<size_t>(space - p));
    what[space - p] = '\0';
    const char* q = space + 1;
    const size_t n = strlen(q);
    if (n == 0 || n >= 8 || strchr(q, ' ') != nullptr) return false;
    memcpy(how, q, n + 1);
    return true;
}

}  // namespace

void MonitorApp::begin(const MonitorAppConfig& config) {
    config_ = config;
    state_ = MonitorAppState{};
    state_.outputs = config.outputs;
    state_.sensors_ok = sensors_.begin();
    state_.display_ok = display_.begin();
    card_ok_ = storage_.begin();
    log_opened_ = false;

    core::MonitorConfig mc = config.monitor;
    if (card_ok_ && config.remember_averages) {
        char buf[160];
        const int n = storage_.read_file(kAveragesPath, buf, sizeof buf);
        StoredAverages stored;
        if (n > 0 && parse_averages(buf, static_cast<size_t>(n), stored)) {
            // The card's memory replaces the config's remembered values; a zero means
            // "never measured" and keeps the config's.
            if (stored.current_a > 0.0f) mc.current_average.initial_value = stored.current_a;
            if (stored.power_w > 0.0f) mc.power_average.initial_value = stored.power_w;
            state_.flights = stored.flights;
            state_.averages_loaded = true;
        }
    }
    monitor_.configure(mc);
    current_average_.configure(mc.current_average);
    telemetry_.configure(config.telemetry, mc);
    beeper_.configure(config.telemetry, mc);
    buzzing_ = false;
    if (buzzer_ != nullptr) buzzer_->set(false);
    sample_ = core::Sample{};
    series_cells_ = series_cells_for(mc.cells_in_series);
    format_series_header(series_cells_, header_);
    was_flying_ = false;
    reversed_check_.configure(mc.flying.min_flying_current_a);
    displayed_ = false;
    last_sync_ms_ = clock_.millis();
    // The log file is created when SD output is first on, not before: no empty files.
    if (card_ok_ && state_.outputs.sd) open_sd_log();
}

void MonitorApp::open_sd_log() {
    log_opened_ = true;
    state_.sd_ok = false;
    if (!storage_.exists(kLogDir) && !storage_.make_dir(kLogDir)) {
        ++state_.sd_errors;
        return;
    }
    // A new file per boot: the first free number.
    for (unsigned i = 1; i <= 9999u; ++i) {
        // Each look-up scans the directory: let the ESP8266's system run between them, or a
        // card with hundreds of logs keeps setup() past its watchdog.
        clock_.sleep_us(0);
        snprintf(state_.log_path, sizeof state_.log_path, "%s/log%04u.csv", kLogDir, i);
        if (storage_.exists(state_.log_path)) continue;
        if (storage_.open_log(state_.log_path) && storage_.append(header_.c_str(), header_.size())) {
            state_.sd_ok = true;
        } else {
            ++state_.sd_errors;
        }
        return;
    }
    state_.log_path[0] = '\0';
    ++state_.sd_errors;
}

MonitorApp::Step MonitorApp::step() {
    handle_serial();
    link_.prompt_if_due(clock_.millis());
    if (!state_.sensors_ok) {
        const uint32_t now_ms = clock_.millis();
        if (now_ms - last_sensor_retry_ms_ >= 1000u) {
            last_sensor_retry_ms_ = now_ms;
            state_.sensors_ok = sensors_.begin();
        }
        if (!state_.sensors_ok) {
            silence_buzzer();
            clock_.sleep_us(10000);
            return Step::SensorError;
        }
    }
    const ReadingLoop::Result r = readings_.next(reading_, config_.poll_us);
    if (r == ReadingLoop::Result::Timeout) return Step::Timeout;
    if (r == ReadingLoop::Result::PackError) {
        silence_buzzer();  // no samples, no pattern: not stuck on mid-beep
        return Step::SensorError;
    }

    make_sample(reading_.time_us, reading_.pack, reading_.taps_ok ? &reading_.taps : nullptr,
                monitor_.config().cells_in_series, monitor_.config().shunt, sample_);
    const core::MonitorStatus& s = monitor_.update(sample_);
    // The monitor feeds its averages only with accepted samples, once initialised, while
    // flying: the twin follows the same rule.
    if (s.sample_valid && s.initialised && s.flying) current_average_.update(s.current_a, s.dt_s);
    ++state_.samples;
    state_.current_reversed = reversed_check_.update(sample_.time_us, sample_.current_a);
    if (s.flying && !was_flying_) ++state_.flights;
    const bool landed = was_flying_ && !s.flying;
    was_flying_ = s.flying;
    write_outputs();
    if (landed && config_.remember_averages) save_averages();
    return Step::Sample;
}

void MonitorApp::write_outputs() {
    const core::MonitorStatus& s = monitor_.status();
    format_series_line(sample_, s, series_cells_, line_);
    if (state_.outputs.uart && link_.connected()) link_.send_data(line_.c_str(), line_.size());
    if (state_.outputs.mavlink && telemetry_port_ != nullptr) {
        uint8_t frames[telemetry::MavlinkTelemetry::kMaxBytesPerUpdate];
        const size_t n = telemetry_.update(sample_, s, frames);
        if (n > 0) telemetry_port_->write(reinterpret_cast<const char*>(frames), n);
    }
    if (buzzer_ != nullptr) {
        // The beeper follows every sample, so switching it back on resumes in step.
        const bool on = beeper_.update(s, state_.current_reversed) && state_.outputs.buzzer;
        if (on != buzzing_) buzzer_->set(on);
        buzzing_ = on;
    }
    const uint32_t now_ms = clock_.millis();
    if (state_.outputs.sd && state_.sd_ok) {
        if (!storage_.append(line_.c_str(), line_.size())) {
            // A failing card is dropped for this boot; the OLED and "status" show it.
            ++state_.sd_errors;
            state_.sd_ok = false;
        } else if (now_ms - last_sync_ms_ >= config_.sd_sync_interval_ms) {
            sync_storage();
        }
    }
    if (state_.outputs.display && state_.display_ok &&
        (!displayed_ || now_ms - last_display_ms_ >= config_.display_interval_ms)) {
        displayed_ = true;
        last_display_ms_ = now_ms;
        draw_display();
    }
}

void MonitorApp::sync_storage() {
    last_sync_ms_ = clock_.millis();
    if (state_.sd_ok && !storage_.sync()) {
        ++state_.sd_errors;
        state_.sd_ok = false;
    }
}

bool MonitorApp::save_averages() {
    if (!card_ok_ || !current_average_.status().valid) return false;
    StoredAverages a;
    a.current_a = current_average_.status().long_avg;
    a.power_w = monitor_.status().long_avg_power_w;
    a.flights = state_.flights;
    telemetry::FixedText<160> text;
    format_averages(a, text);
    if (text.overflow() || (!storage_.exists(kLogDir) && !storage_.make_dir(kLogDir)) ||
        !storage_.write_file(kAveragesPath, text.c_str(), text.size())) {
        ++state_.sd_errors;
        return false;
    }
    ++state_.averages_saved;
    return true;
}

void MonitorApp::draw_display() {
    MonitorPage page;
    page.sample = &sample_;
    page.status = &monitor_.status();
    page.counters = readings_.counters();
    page.sd_ok = state_.sd_ok || !state_.outputs.sd;
    page.current_reversed = state_.current_reversed;
    draw_monitor_page(display_, page);
}

void MonitorApp::handle_serial() {
    for (;;) {
        const LineLink::Event e = link_.poll();
        if (e == LineLink::Event::None) return;
        if (e == LineLink::Event::Hello) {
            if (state_.outputs.uart) link_.send_data(header_.c_str(), header_.size());
        } else {
            handle_command(link_.command());
        }
    }
}

void MonitorApp::handle_command(const char* cmd) {
    char what[8] = {};
    char how[8] = {};
    if (split_out_command(cmd, what, how)) {
        bool on = false;
        bool* target = nullptr;
        if (strcmp(what, "uart") == 0) target = &state_.outputs.uart;
        if (strcmp(what, "sd") == 0) target = &state_.outputs.sd;
        if (strcmp(what, "oled") == 0) target = &state_.outputs.display;
        if (strcmp(what, "mavlink") == 0) target = &state_.outputs.mavlink;
        if (strcmp(what, "buzzer") == 0) target = &state_.outputs.buzzer;
        if (target != nullptr && parse_switch(how, on)) {
            const bool uart_turned_on = target == &state_.outputs.uart && on && !*target;
            *target = on;
            if (uart_turned_on && link_.connected()) link_.send_data(header_.c_str(), header_.size());
            if (target == &state_.outputs.sd && !on) sync_storage();
            if (target == &state_.outputs.sd && on && card_ok_ && !log_opened_) open_sd_log();
            if (target == &state_.outputs.buzzer && !on) silence_buzzer();
            if (target == &state_.outputs.display && !on && state_.display_ok) {
                display_.clear();
                display_.show();
            }
            send_status_note();
            return;
        }
    } else if (strcmp(cmd, "status") == 0) {
        send_status_note();
        return;
    } else if (strcmp(cmd, "save") == 0) {
        link_.send_note(save_averages() ? "averages saved" : "averages not saved (no card or no flight yet)");
        return;
    }
    link_.send_note("unknown command; try: status, save, out uart|sd|oled|mavlink|buzzer on|off");
}

void MonitorApp::silence_buzzer() {
    if (buzzer_ != nullptr && buzzing_) buzzer_->set(false);
    buzzing_ = false;
}

void MonitorApp::send_status_note() {
    const ReadingCounters c = readings_.counters();
    telemetry::FixedText<224> t;
    t.append("samples=");
    t.append_uint(state_.samples);
    t.append(" missed=");
    t.append_uint(c.missed);
    t.append(" timeouts=");
    t.append_uint(c.ready_timeouts);
    t.append(" pack_errors=");
    t.append_uint(c.pack_errors);
    t.append(" tap_errors=");
    t.append_uint(c.tap_errors);
    t.append(sensors_.has_taps() ? " taps=yes" : " taps=none");
    t.append(" sd=");
    t.append(state_.sd_ok ? state_.log_path : "off");
    t.append(" sd_errors=");
    t.append_uint(state_.sd_errors);
    t.append(" flights=");
    t.append_uint(state_.flights);
    if (state_.current_reversed) t.append(" current=reversed");
    t.append(" out=");
    // The outputs that are on, comma-separated with no empty items ("none" for none), so a
    // host can split the list.
    const char* on[5] = {};
    size_t n = 0;
    if (state_.outputs.uart) on[n++] = "uart";
    if (state_.outputs.sd) on[n++] = "sd";
    if (state_.outputs.display) on[n++] = "oled";
    if (state_.outputs.mavlink && telemetry_port_ != nullptr) on[n++] = "mavlink";
    if (state_.outputs.buzzer && buzzer_ != nullptr) on[n++] = "buzzer";
    for (size_t i = 0; i < n; ++i) {
        if (i > 0) t.append_char(',');
        t.append(on[i]);
    }
    if (n == 0) t.append("none");
    link_.send_note(t.c_str());
}

}  // namespace fw
}  // namespace battsim
