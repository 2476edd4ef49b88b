#include "host/sim/sensor.h"

#include "core/monitor.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace battsim {
namespace host {
namespace sim {

namespace {

constexpr double kBusLsbV = 0.00125;
constexpr double kShuntLsbMv = 0.0025;
constexpr double kTapLsbV = 0.008;

int32_t quantise(double value, double lsb, int32_t lo, int32_t hi) {
    const double q = std::floor(value / lsb + 0.5);
    if (!(q >= lo)) return lo;
    if (q > hi) return hi;
    return static_cast<int32_t>(q);
}

// Integer division rounding half away from zero (b > 0).
int64_t round_div(int64_t a, int64_t b) { return a >= 0 ? (a + b / 2) / b : -((-a + b / 2) / b); }

// `value` in units of 10^-decimals, as text.
void append_fixed(std::string& out, int64_t value, int decimals) {
    char buf[64];
    // A 64-bit value has at most 19 digits; the bound also tells GCC the text fits.
    decimals = decimals < 0 ? 0 : (decimals > 18 ? 18 : decimals);
    int64_t scale = 1;
    for (int i = 0; i < decimals; ++i) scale *= 10;
    const bool neg = value < 0;
    const uint64_t mag = neg ? 0u - static_cast<uint64_t>(value) : static_cast<uint64_t>(value);
    const unsigned long long whole = mag / static_cast<uint64_t>(scale);
    const unsigned long long frac = mag % static_cast<uint64_t>(scale);
    if (decimals > 0) {
        std::snprintf(buf, sizeof buf, "%s%llu.%0*llu", neg ? "-" : "", whole, decimals, frac);
    } else {
        std::snprintf(buf, sizeof buf, "%s%llu", neg ? "-" : "", whole);
    }
    out += buf;
}

}  // namespace

const std::vector<SimLogFormatEntry>& sim_log_formats() {
    static const std::vector<SimLogFormatEntry> formats{
        {SimLogFormat::Raw, "raw", ".csv", "4 cells only"},
        {SimLogFormat::Csv, "csv", ".csv", ""},
        {SimLogFormat::Radio, "edgetx", ".csv",
         "a radio's telemetry log: pack voltage and current in 0.1 V and 0.1 A steps every log.interval_s, no cells"},
        {SimLogFormat::DataFlash, "dataflash", ".bin", "an ArduPilot .bin log: BAT and BCL at 10 Hz"},
        {SimLogFormat::ULog, "ulog", ".ulg", "a PX4 .ulg log: battery_status at 5 Hz"},
    };
    return formats;
}

const char* sim_log_format_name(SimLogFormat f) {
    for (const SimLogFormatEntry& e : sim_log_formats())
        if (e.format == f) return e.name;
    return "csv";
}

const char* sim_log_extension(SimLogFormat f) {
    for (const SimLogFormatEntry& e : sim_log_formats())
        if (e.format == f) return e.extension;
    return ".csv";
}

bool parse_sim_log_format(const std::string& name, SimLogFormat& out) {
    for (const SimLogFormatEntry& e : sim_log_formats()) {
        if (name == e.name) {
            out = e.format;
            return true;
        }
    }
    return false;
}

std::vector<std::string> sim_log_format_names() {
    std::vector<std::string> names;
    for (const SimLogFormatEntry& e : sim_log_formats()) names.emplace_back(e.name);
    return names;
}

std::string sim_log_format_help() {
    const std::vector<SimLogFormatEntry>& formats = sim_log_formats();
    std::string help;
    for (size_t i = 0; i < formats.size(); ++i) {
        if (i > 0) help += i + 1 == formats.size() ? " or " : ", ";
        help += formats[i].name;
        if (formats[i].description[0] != '\0') help += std::string(" (") + formats[i].description + ")";
    }
    return help;
}

float firmware_current_ma(int32_t shunt_count, const core::ShuntCalibration& shunt) {
    const float shunt_mv = static_cast<float>(shunt_count) * 0.0025f;
    return core::current_ma_from_shunt_mv(shunt_mv, shunt);
}

void SensorChain::configure(const SensorParams& params, int cells, uint64_t seed) {
    p_ = params;
    cells_ = cells;
    timing_rng_ = Rng::stream(seed, 11);
    noise_rng_ = Rng::stream(seed, 12);
    fault_rng_ = Rng::stream(seed, 13);
    tap_noise_rng_ = Rng::stream(seed, 15);
    Rng unit_rng = Rng::stream(seed, 14);
    if (p_.unit_given) {
        unit_ = p_.unit;
    } else {
        unit_ = SensorUnit{};
        unit_.bus_gain_error = unit_rng.normal(0.0, p_.bus_gain_sd);
        for (int k = 0; k + 1 < cells_; ++k) {
            unit_.tap_gain_error[k] = unit_rng.normal(0.0, p_.tap_gain_sd);
            unit_.tap_offset_v[k] = unit_rng.normal(0.0, p_.tap_offset_sd_v);
        }
    }
    acc226_ = Accumulator{};
    acc3221_ = Accumulator{};
    // Both chips start converting at power-on; the INA3221's cycle has its own phase.
    next_ready226_s_ = p_.period_ms * 1e-3;
    next_ready3221_s_ = timing_rng_.uniform(0.2, 1.0) * p_.tap_period_ms * 1e-3;
    next_read_s_ = (p_.first_read_ms + timing_rng_.uniform(0.0, p_.period_ms)) * 1e-3;
    stall_left_ = 0;
    next_stall_s_ = p_.stall_rate_per_s > 0 ? next_read_s_ + timing_rng_.exponential(1.0 / p_.stall_rate_per_s) : 1e300;
    have226_ = have3221_ = false;
    loose_open_ = false;
    loose_switch_s_ = 0.0;
    if (p_.faults.loose_tap > 0) loose_switch_s_ = fault_rng_.exponential(p_.faults.loose_contact_mean_s * p_.faults.loose_ground_factor);
    if (p_.faults.missed_burst_rate_per_min > 0) {
        burst_start_s_ = fault_rng_.exponential(60.0 / p_.faults.missed_burst_rate_per_min);
        burst_end_s_ = burst_start_s_ + fault_rng_.uniform(p_.faults.missed_burst_min_s, p_.faults.missed_burst_max_s);
    } else {
        burst_start_s_ = burst_end_s_ = 1e300;
    }
    stats_ = SensorStats{};
}

void SensorChain::finish_ina226() {
    if (acc226_.span_s <= 0.0) return;
    const double bus = acc226_.bus_v_s / acc226_.span_s * (1.0 + unit_.bus_gain_error) + noise_rng_.normal(0.0, p_.bus_noise_v);
    const double shunt = acc226_.shunt_mv_s / acc226_.span_s + noise_rng_.normal(0.0, p_.shunt_noise_mv);
    bus_count_ = quantise(bus, kBusLsbV, 0, 32767);            // bus register: 0..40.96 V
    shunt_count_ = quantise(shunt, kShuntLsbMv, -32768, 32767);  // ±81.92 mV
    if (shunt_count_ <= -32768 || shunt_count_ >= 32767) ++stats_.current_clipped;
    have226_ = true;
    acc226_ = Accumulator{};
}

void SensorChain::finish_ina3221() {
    if (acc3221_.span_s <= 0.0) return;
    for (int k = 0; k + 1 < cells_; ++k) {
        const double v = acc3221_.taps_v_s[k] / acc3221_.span_s * (1.0 + unit_.tap_gain_error[k]) + unit_.tap_offset_v[k] +
                         tap_noise_rng_.normal(0.0, p_.tap_noise_v);
        tap_count_[k] = quantise(v, kTapLsbV, -4096, 4095);  // 13-bit signed register
    }
    have3221_ = true;
    acc3221_ = Accumulator{};
}

void SensorChain::schedule_after(double read_time_s) {
    if (stall_left_ > 0) {
        --stall_left_;
        next_read_s_ = read_time_s + timing_rng_.uniform(p_.stall_more_min_s, p_.stall_more_max_s);
        return;
    }
    if (read_time_s >= next_stall_s_) {
        // An SD-card write blocks the loop; conversions finishing meanwhile are lost.
        ++stats_.stalls;
        stall_left_ = timing_rng_.uniform_int(0, p_.stall_more_max);
        next_read_s_ = read_time_s + timing_rng_.uniform(p_.stall_first_min_s, p_.stall_first_max_s);
        next_stall_s_ = next_read_s_ + timing_rng_.exponential(1.0 / p_.stall_rate_per_s);
        return;
    }
    double t = next_ready226_s_ + timing_rng_.uniform(0.1, p_.latency_max_ms) * 1e-3;
    if (timing_rng_.chance(p_.late_read_rate_per_s * p_.period_ms * 1e-3)) {
        ++stats_.late_reads;
        t += timing_rng_.uniform(p_.late_read_min_ms, p_.late_read_max_ms) * 1e-3;
    }
    next_read_s_ = t;
}

void SensorChain::emit(double read_time_s, std::vector<LogRecord>& out) {
    ++stats_.reads;
    bool drop = false;
    const SensorFaults& f = p_.faults;
    if (f.missed_probability > 0.0 && fault_rng_.chance(f.missed_probability)) drop = true;
    while (read_time_s >= burst_end_s_) {
        burst_start_s_ = burst_end_s_ + fault_rng_.exponential(60.0 / f.missed_burst_rate_per_min);
        burst_end_s_ = burst_start_s_ + fault_rng_.uniform(f.missed_burst_min_s, f.missed_burst_max_s);
    }
    if (read_time_s >= burst_start_s_) drop = true;
    if (!have226_ || (cells_ >= 2 && !have3221_)) drop = true;  // nothing converted yet
    if (drop) {
        if (have226_) ++stats_.dropped;
        return;
    }
    LogRecord r;
    r.read_time_s = read_time_s;
    r.time_ms = static_cast<int64_t>(std::floor(read_time_s * 1000.0));
    r.bus_count = bus_count_;
    r.shunt_count = shunt_count_;
    for (int k = 0; k + 1 < cells_; ++k) r.tap_count[k] = tap_count_[k];
    const double temp = temperature_c_ + noise_rng_.normal(0.0, p_.temperature_noise_c);
    r.temperature_dc = static_cast<int32_t>(std::floor(temp * 10.0 + 0.5));
    out.push_back(r);
}

void SensorChain::feed(double t_s, double dt_s, const TrueValues& v, bool airborne, std::vector<LogRecord>& out) {
    const double t_end = t_s + dt_s;
    const SensorFaults& f = p_.faults;

    // Loose balance lead: switch between contact and open at random times.
    double open_weight = 0.0;  // fraction of this step the tap is open
    if (f.loose_tap > 0 && f.loose_tap < cells_) {
        double t = t_s;
        while (loose_switch_s_ < t_end) {
            if (loose_open_) open_weight += loose_switch_s_ - t;
            t = loose_switch_s_ > t ? loose_switch_s_ : t;
            loose_open_ = !loose_open_;
            if (loose_open_) {
                ++stats_.loose_episodes;
                loose_switch_s_ = t + fault_rng_.exponential(f.loose_open_mean_s);
            } else {
                const double mean = f.loose_contact_mean_s * (airborne ? 1.0 : f.loose_ground_factor);
                loose_switch_s_ = t + fault_rng_.exponential(mean);
            }
        }
        if (loose_open_) open_weight += t_end - t;
        stats_.loose_open_s += open_weight;
        open_weight /= dt_s;
    }

    // Current as the faulty sensor sees it, then the shunt voltage the calibration implies.
    const double sensed_a = v.current_a * (1.0 + f.current_gain_error) + f.current_offset_a;
    const double shunt_mv = (sensed_a * 1000.0 - static_cast<double>(p_.shunt.offset_ma)) *
                            static_cast<double>(p_.shunt.scale_mv_per_10a) / 10000.0;

    const double ground_v = v.current_a * p_.ground_lead_ohm;  // the monitor's ground above the pack's negative
    acc226_.bus_v_s += (v.voltage_v - ground_v - v.current_a * p_.bus_lead_ohm) * dt_s;
    acc226_.shunt_mv_s += shunt_mv * dt_s;
    acc226_.span_s += dt_s;
    double tap = 0.0;
    for (int k = 0; k + 1 < cells_; ++k) {
        tap += v.cell_v[k];
        double tv = tap - ground_v;
        // An open input floats to a few tens of millivolts.
        if (k + 1 == f.loose_tap) tv = tv * (1.0 - open_weight) + 0.02 * open_weight;
        acc3221_.taps_v_s[k] += tv * dt_s;
    }
    acc3221_.span_s += dt_s;
    temperature_c_ = v.temperature_c;

    while (t_end >= next_ready226_s_) {
        finish_ina226();
        next_ready226_s_ += p_.period_ms * 1e-3;
    }
    while (t_end >= next_ready3221_s_) {
        finish_ina3221();
        next_ready3221_s_ += p_.tap_period_ms * 1e-3;
    }
    while (t_end >= next_read_s_) {
        const double r = next_read_s_;
        emit(r, out);
        schedule_after(r);
    }
}

std::string format_header(SimLogFormat f, int cells) {
    if (f == SimLogFormat::Raw) return std::string();
    if (f == SimLogFormat::Radio) return "Date,Time,RxBt(V),Curr(A)\n";
    std::string h = "time_s,voltage_v,current_a";
    for (int c = 1; c <= cells; ++c) h += ",cell" + std::to_string(c) + "_v";
    h += ",temperature_c\n";
    return h;
}

void format_record(SimLogFormat f, int cells, const core::ShuntCalibration& shunt, const LogRecord& r,
                   std::string& out) {
    // Voltages in units of 10 µV: every ADC step is a whole number of them.
    const int64_t bus = static_cast<int64_t>(r.bus_count) * 125;
    int64_t cell[kMaxCells];
    int64_t prev = 0;
    for (int c = 0; c < cells; ++c) {
        const int64_t tap = c + 1 < cells ? static_cast<int64_t>(r.tap_count[c]) * 800 : bus;
        cell[c] = tap - prev;
        prev = tap;
    }
    const float current_ma = firmware_current_ma(r.shunt_count, shunt);
    if (f == SimLogFormat::Radio) {
        // A fixed date; the clock from the log's start (the simulation starts at midnight).
        const int64_t ms = r.time_ms;
        char clock[40];
        std::snprintf(clock, sizeof clock, "2026-01-%02lld,%02lld:%02lld:%02lld.%03lld,",
                      static_cast<long long>(1 + ms / 86400000), static_cast<long long>(ms / 3600000 % 24),
                      static_cast<long long>(ms / 60000 % 60), static_cast<long long>(ms / 1000 % 60),
                      static_cast<long long>(ms % 1000));
        out += clock;
        append_fixed(out, round_div(bus, 10000), 1);  // 10 µV units → 0.1 V
        out += ',';
        append_fixed(out, static_cast<int64_t>(std::llround(static_cast<double>(current_ma) / 100.0)), 1);
        out += '\n';
        return;
    }
    if (f == SimLogFormat::Raw) {
        append_fixed(out, r.time_ms, 0);
        out += ',';
        append_fixed(out, round_div(bus, 1000), 2);
        for (int c = 0; c < cells; ++c) {
            out += ',';
            append_fixed(out, round_div(cell[c], 1000), 2);
        }
        out += ',';
        append_fixed(out, static_cast<int64_t>(std::llround(static_cast<double>(current_ma) * 100.0)), 2);
        out += ',';
        append_fixed(out, round_div(r.shunt_count, 4), 2);
        out += ",\n";
    } else {
        append_fixed(out, r.time_ms, 3);
        out += ',';
        append_fixed(out, bus, 5);
        out += ',';
        append_fixed(out, static_cast<int64_t>(std::llround(static_cast<double>(current_ma))), 3);
        for (int c = 0; c < cells; ++c) {
            out += ',';
            append_fixed(out, cell[c], 5);
        }
        out += ',';
        append_fixed(out, r.temperature_dc, 1);
        out += '\n';
    }
}

RecordValues record_values(int cells, const core::ShuntCalibration& shunt, const LogRecord& r) {
    RecordValues v;
    v.voltage_v = r.bus_count * kBusLsbV;
    double prev = 0;
    for (int c = 0; c < cells; ++c) {
        const double tap = c + 1 < cells ? r.tap_count[c] * kTapLsbV : v.voltage_v;
        v.cell_v[c] = tap - prev;
        prev = tap;
    }
    v.current_a = static_cast<double>(std::llround(static_cast<double>(firmware_current_ma(r.shunt_count, shunt)))) / 1000.0;
    v.temperature_c = r.temperature_dc / 10.0;
    return v;
}

uint8_t nameable_fault_causes(const SensorFaults& faults) {
    uint8_t causes = 0;
    if (faults.current_offset_a != 0.0) causes |= core::kFaultCurrentOffset;
    if (faults.loose_tap != 0) causes |= core::kFaultCells;
    if (faults.missed_burst_rate_per_min > 0.0 && faults.missed_burst_max_s > 0.0) causes |= core::kFaultSampleGap;
    return causes;
}

}  // namespace sim
}  // namespace host
}  // namespace battsim
