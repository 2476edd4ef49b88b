// The register-level INA226/INA3221 driver against a fake I²C bus holding the two chips'
// registers: configuration words, identification, scaling and every failed read, with the
// expected values worked out by hand from TI's data sheets (SBOS547, SBOS576).
#include <map>
#include <utility>
#include <vector>

#include "app/ina_sensors.h"
#include "app/reading_loop.h"
#include "mock_hardware.h"
#include "test_firmware_support.h"

using namespace battsim;

namespace {

// Registers per address; a read of a register listed in `fail` (register 0xFF there: any
// register of that address) fails, as a missing acknowledge or a short read does on the wire.
struct FakeBus : fw::I2cBus {
    std::map<std::pair<uint8_t, uint8_t>, uint16_t> regs;
    std::vector<std::pair<uint8_t, uint8_t>> fail;
    std::vector<std::pair<uint8_t, uint16_t>> config_writes;  // (address, value) written to register 0
    // The INA226 clears its ready flag when Mask/Enable is read; the INA3221 likewise.
    bool write_register(uint8_t address, uint8_t reg, uint16_t value) override {
        if (!regs.count({address, fw::ina::kRegDieId})) return false;  // nobody there
        regs[{address, reg}] = value;
        if (reg == fw::ina::kRegConfig) config_writes.push_back({address, value});
        return true;
    }
    int id_reads = 0;  // reads of the manufacturer ID at 0x41 (the tap chip's probe)
    bool read_register(uint8_t address, uint8_t reg, uint16_t& value) override {
        if (address == 0x41 && reg == fw::ina::kRegManufacturerId) ++id_reads;
        for (const auto& f : fail)
            if (f.first == address && (f.second == reg || f.second == 0xFF)) return false;
        const auto it = regs.find({address, reg});
        if (it == regs.end()) return false;
        value = it->second;
        if (reg == fw::ina::kIna226RegMaskEnable && address == 0x40) it->second &= ~fw::ina::kIna226ConversionReady;
        if (reg == fw::ina::kIna3221RegMaskEnable && address == 0x41) it->second &= ~fw::ina::kIna3221ConversionReady;
        return true;
    }
    void add_chip(uint8_t address, uint16_t die) {
        regs[{address, fw::ina::kRegManufacturerId}] = 0x5449;
        regs[{address, fw::ina::kRegDieId}] = die;
        regs[{address, fw::ina::kRegConfig}] = 0;
    }
};

// A board with the INA226 alone (0x40), begun.
struct PackOnly {
    FakeBus bus;
    fw::InaSensors s{bus};
    PackOnly() {
        bus.add_chip(0x40, 0x2260);
        REQUIRE(s.begin());
        REQUIRE_FALSE(s.has_taps());
    }
};

// The monitor's board: the INA226 at 0x40, the INA3221 at 0x41 (a fixture: `bus`, `s`).
struct Board {
    FakeBus bus;
    fw::InaSensors s{bus};
    Board() {
        bus.add_chip(0x40, 0x2260);
        bus.add_chip(0x41, 0x3220);
    }
};

}  // namespace

TEST_CASE("INA driver: the configuration words are the data sheets' fields", "[firmware]") {
    // INA226: bit 14 (reads 1) | AVG 010 (16) | VBUSCT 101 (2.116 ms) | VSHCT 101 | MODE 111
    // = 0100 0101 0110 1111.
    CHECK(fw::ina::kIna226Config == 0x456F);
    // INA226 period from those fields: 2 conversions × 2116 µs × 16 averages (readings.h).
    CHECK(fw::kIna226PeriodUs == 2u * 2116u * 16u);
    // INA3221: channels 1–3 on (14:12 = 111) | AVG 010 | VBUSCT 100 (1.1 ms) | VSHCT 100 |
    // MODE 010 (bus, single-shot) = 0111 0101 0010 0010; its three channels take
    // 3 × 16 × 1.1 ms = 52.8 ms, inside one INA226 period.
    CHECK(fw::ina::kIna3221Config == 0x7522);
    CHECK(3u * fw::kIna3221Averages * fw::kIna3221ConversionUs < fw::kIna226PeriodUs);
}

TEST_CASE_METHOD(Board, "INA driver: begin identifies both chips and configures them", "[firmware]") {
    REQUIRE(s.begin());
    CHECK(s.has_taps());
    REQUIRE(bus.config_writes.size() == 2);
    CHECK(bus.config_writes[0] == std::make_pair(uint8_t{0x40}, uint16_t{0x456F}));
    CHECK(bus.config_writes[1] == std::make_pair(uint8_t{0x41}, uint16_t{0x7522}));  // the first tap conversion

    SECTION("no tap chip: the pack alone, and no tap errors counted") {
        PackOnly board_p;
        FakeBus& pack_only = board_p.bus;
        fw::InaSensors& p = board_p.s;
        fw::TapReading t;
        CHECK_FALSE(p.read_taps(t));
        pack_only.regs[{0x40, fw::ina::kIna226RegMaskEnable}] = fw::ina::kIna226ConversionReady;
        pack_only.regs[{0x40, fw::ina::kIna226RegBus}] = 13328;
        pack_only.regs[{0x40, fw::ina::kIna226RegShunt}] = 268;
        fw::host::MockClock clock;
        fw::ReadingLoop loop(p, clock);
        fw::Reading r;
        REQUIRE(loop.next(r) == fw::ReadingLoop::Result::Reading);
        CHECK_FALSE(r.taps_ok);
        CHECK(loop.counters().tap_errors == 0);
    }
    SECTION("an INA3221 strapped to the INA226's address is no pack sensor") {
        FakeBus clash;
        clash.add_chip(0x40, 0x3220);
        fw::InaSensors c(clash);
        CHECK_FALSE(c.begin());
        CHECK(clash.config_writes.empty());
    }
    SECTION("another maker's chip, or none, at the pack address") {
        FakeBus other;
        other.add_chip(0x40, 0x2260);
        other.regs[{0x40, fw::ina::kRegManufacturerId}] = 0x4D41;
        fw::InaSensors o(other);
        CHECK_FALSE(o.begin());
        FakeBus none;
        fw::InaSensors n(none);
        CHECK_FALSE(n.begin());
    }
    SECTION("a configuration that does not read back is refused") {
        FakeBus flaky;
        flaky.add_chip(0x40, 0x2260);
        flaky.fail.push_back({0x40, fw::ina::kRegConfig});
        fw::InaSensors f(flaky);
        CHECK_FALSE(f.begin());
        // ... and one that reads back another word (a write the chip did not take).
        struct Stubborn : FakeBus {
            bool write_register(uint8_t address, uint8_t reg, uint16_t value) override {
                return FakeBus::write_register(address, reg, reg == fw::ina::kRegConfig ? 0x4127 : value);
            }
        } stubborn;
        stubborn.add_chip(0x40, 0x2260);
        fw::InaSensors g(stubborn);
        CHECK_FALSE(g.begin());
    }
    SECTION("a tap chip that answers late is found again") {
        PackOnly board_l;
        FakeBus& late = board_l.bus;
        fw::InaSensors& l = board_l.s;
        late.add_chip(0x41, 0x3220);
        fw::TapReading t;
        for (int k = 1; k < fw::InaSensors::kTapRetryReadings; ++k) CHECK_FALSE(l.read_taps(t));
        CHECK_FALSE(l.has_taps());
        CHECK_FALSE(l.read_taps(t));  // the retry: found and started, no reading yet
        CHECK(l.has_taps());
        CHECK(late.config_writes.back() == std::make_pair(uint8_t{0x41}, uint16_t{0x7522}));
    }
    SECTION("a tap chip still missing is looked for once every 128 readings, not at every one") {
        PackOnly board_m;
        FakeBus& missing = board_m.bus;
        fw::InaSensors& m = board_m.s;
        fw::TapReading t;
        missing.id_reads = 0;  // begin()'s own probe
        int probes = 0;
        for (int k = 0; k < 3 * fw::InaSensors::kTapRetryReadings; ++k) {
            CHECK_FALSE(m.read_taps(t));
            probes += missing.id_reads;  // a probe reads the (absent) chip's ID first
            missing.id_reads = 0;
        }
        CHECK(probes == 3);
    }
}

TEST_CASE_METHOD(Board, "INA driver: registers become readings in the firmware's exact units", "[firmware]") {
    REQUIRE(s.begin());

    // Ready flag: bit 3 of Mask/Enable, cleared by the read.
    CHECK_FALSE(s.conversion_ready());
    bus.regs[{0x40, fw::ina::kIna226RegMaskEnable}] = 0x0408;  // CNVR and CVRF set
    CHECK(s.conversion_ready());
    CHECK_FALSE(s.conversion_ready());

    // Bus 13328 × 1.25 mV = 16.66 V = 1,666,000 × 10 µV; shunt 268 × 2.5 µV = 0.67 mV =
    // 6,700 × 0.1 µV; a negative shunt word (0xFF00 = −256) is −0.64 mV = −6,400.
    bus.regs[{0x40, fw::ina::kIna226RegBus}] = 13328;
    bus.regs[{0x40, fw::ina::kIna226RegShunt}] = 268;
    fw::PackReading p;
    REQUIRE(s.read_pack(p));
    CHECK(p.bus_10uv == 1666000);
    CHECK(p.shunt_100nv == 6700);
    bus.regs[{0x40, fw::ina::kIna226RegShunt}] = 0xFF00;
    REQUIRE(s.read_pack(p));
    CHECK(p.shunt_100nv == -6400);
    // The extremes: full-scale shunt ±81.92 mV, bus 40.96 V less one step.
    bus.regs[{0x40, fw::ina::kIna226RegShunt}] = 0x8000;
    bus.regs[{0x40, fw::ina::kIna226RegBus}] = 0x7FFF;
    REQUIRE(s.read_pack(p));
    CHECK(p.shunt_100nv == -819200);
    CHECK(p.bus_10uv == 32767 * 125);
    // Bit 15 of the bus register is always 0: set, the word was garbled on the bus.
    bus.regs[{0x40, fw::ina::kIna226RegBus}] = 0x8000 | 13328;
    CHECK_FALSE(s.read_pack(p));

    // Taps: bits 15:3 in 8 mV steps, so 0x0D00 (3328) is 416 × 8 = 3328 mV and 0x1A08 (6664)
    // is 833 × 8 = 6664 mV; a negative word 0xFFF8 is −1 × 8 = −8 mV; the low bits are not data.
    bus.regs[{0x41, 0x02}] = 0x0D00;  // 3328 mV
    bus.regs[{0x41, 0x04}] = 0x1A08 | 0x7;
    bus.regs[{0x41, 0x06}] = 0xFFF8;
    fw::TapReading t;
    bus.regs[{0x41, fw::ina::kIna3221RegMaskEnable}] = 0;  // the chip answers: still converting
    CHECK_FALSE(s.read_taps(t));                           // no cells this sample
    CHECK(bus.config_writes.size() == 2);                  // ... and the conversion is left to finish
    CHECK_FALSE(s.read_taps(t));                           // unfinished twice: lost, so restarted
    CHECK(bus.config_writes.size() == 3);
    bus.regs[{0x41, fw::ina::kIna3221RegMaskEnable}] = fw::ina::kIna3221ConversionReady;
    REQUIRE(s.read_taps(t));
    CHECK(t.tap_mv[0] == 3328);
    CHECK(t.tap_mv[1] == 6664);
    CHECK(t.tap_mv[2] == -8);
    CHECK(bus.config_writes.size() == 4);  // each reading starts the next conversion
    CHECK(bus.config_writes.back() == std::make_pair(uint8_t{0x41}, uint16_t{0x7522}));
    // The ready flag is what counts, not the data registers: cleared by the read, the next
    // call finds it unset and reads no taps, and leaves the conversion it started to finish.
    CHECK_FALSE(s.read_taps(t));
    CHECK(bus.config_writes.size() == 4);
    bus.regs[{0x41, fw::ina::kIna3221RegMaskEnable}] = fw::ina::kIna3221ConversionReady;
    REQUIRE(s.read_taps(t));  // finished: read, and the next started
    CHECK(bus.config_writes.size() == 5);
    CHECK_FALSE(s.read_taps(t));  // unfinished once after a good reading: still left alone
    CHECK(bus.config_writes.size() == 5);
    CHECK_FALSE(s.read_taps(t));  // twice: restarted ...
    CHECK(bus.config_writes.size() == 6);
    CHECK_FALSE(s.read_taps(t));  // ... and the restart is given its reading to finish
    CHECK(bus.config_writes.size() == 6);
    CHECK_FALSE(s.read_taps(t));
    CHECK(bus.config_writes.size() == 7);
    // A failed read of the ready flag restarts the conversion (the chip may have reset).
    bus.fail = {{0x41, fw::ina::kIna3221RegMaskEnable}};
    CHECK_FALSE(s.read_taps(t));
    CHECK(bus.config_writes.size() == 8);
    bus.fail.clear();

    // The INA226 reset to its defaults by a brown-out is configured again within 256 readings.
    bus.regs[{0x40, fw::ina::kRegConfig}] = 0x4127;
    bus.regs[{0x40, fw::ina::kIna226RegBus}] = 13328;
    const size_t before = bus.config_writes.size();
    for (int k = 0; k < fw::InaSensors::kConfigCheckReadings; ++k) REQUIRE(s.read_pack(p));
    REQUIRE(bus.config_writes.size() == before + 1);
    CHECK(bus.config_writes.back() == std::make_pair(uint8_t{0x40}, uint16_t{0x456F}));
    for (int k = 0; k < fw::InaSensors::kConfigCheckReadings; ++k) REQUIRE(s.read_pack(p));
    CHECK(bus.config_writes.size() == before + 1);  // configured: read back, not written
}

TEST_CASE_METHOD(Board, "INA driver: a failed register read is a failed reading, never a zero", "[firmware]") {
    REQUIRE(s.begin());
    bus.regs[{0x40, fw::ina::kIna226RegBus}] = 13328;
    bus.regs[{0x40, fw::ina::kIna226RegShunt}] = 268;
    bus.regs[{0x41, 0x02}] = 0x0D00;
    bus.regs[{0x41, 0x04}] = 0x1A00;
    bus.regs[{0x41, 0x06}] = 0x2700;
    fw::host::MockClock clock;
    fw::ReadingLoop loop(s, clock);
    fw::Reading r;
    auto ready = [this] {
        bus.regs[{0x40, fw::ina::kIna226RegMaskEnable}] = fw::ina::kIna226ConversionReady;
        bus.regs[{0x41, fw::ina::kIna3221RegMaskEnable}] = fw::ina::kIna3221ConversionReady;
    };
    ready();
    REQUIRE(loop.next(r) == fw::ReadingLoop::Result::Reading);
    CHECK(r.taps_ok);
    CHECK(r.pack.bus_10uv == 1666000);

    bus.fail.push_back({0x41, 0x04});  // one tap channel's read fails
    ready();
    REQUIRE(loop.next(r) == fw::ReadingLoop::Result::Reading);
    CHECK_FALSE(r.taps_ok);
    CHECK(loop.counters().tap_errors == 1);

    bus.fail = {{0x40, fw::ina::kIna226RegShunt}};  // the pack's shunt read fails
    ready();
    CHECK(loop.next(r) == fw::ReadingLoop::Result::PackError);
    CHECK(loop.counters().pack_errors == 1);

    bus.fail = {{0x40, 0xFF}};  // the INA226 is gone: its flag never reads, the loop times out
    CHECK(loop.next(r) == fw::ReadingLoop::Result::Timeout);
    CHECK(loop.counters().ready_timeouts == 1);
}
