// battsim log against a fake device on pseudo-terminal pairs: the handshake, a link that
// drops mid-line, a device that comes back (as the same stream and after a reset), and
// the file growing only by whole, verified lines, each exactly once.
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <thread>
#include <vector>

#include "host/serial/line_protocol.h"
#include "host/serial/serial_logger.h"
#include "test_firmware_support.h"

using namespace battsim::host::serial;
using Clock = std::chrono::steady_clock;

namespace {

// One pty pair standing for the device on the far side of a USB cable. The logger is
// given a symlink path, re-pointed at each new pair, as udev does for a re-plugged adapter.
class FakeDevice {
public:
    explicit FakeDevice(std::string link) : link_(std::move(link)) {}
    ~FakeDevice() { unplug(); }

    void plug() {
        // Close-on-exec: a `battsim log` child must not hold the device side open, or
        // unplugging would never reach it.
        master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
        REQUIRE(master_ >= 0);
        REQUIRE(grantpt(master_) == 0);
        REQUIRE(unlockpt(master_) == 0);
        const std::string slave = ptsname(master_);
        // Raw before anyone talks, so the line discipline neither echoes nor rewrites.
        const int s = ::open(slave.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
        REQUIRE(s >= 0);
        termios tio;
        REQUIRE(tcgetattr(s, &tio) == 0);
        cfmakeraw(&tio);
        REQUIRE(tcsetattr(s, TCSANOW, &tio) == 0);
        slave_fd_ = s;  // kept open while plugged: the master then never reads EIO
        ::unlink(link_.c_str());
        REQUIRE(::symlink(slave.c_str(), link_.c_str()) == 0);
        input_.clear();
    }
    void unplug() {
        if (master_ < 0) return;
        ::unlink(link_.c_str());
        ::close(master_);
        ::close(slave_fd_);
        master_ = -1;
        slave_fd_ = -1;
    }
    void send(const std::string& bytes) {
        size_t done = 0;
        while (done < bytes.size()) {
            const ssize_t n = ::write(master_, bytes.data() + done, bytes.size() - done);
            REQUIRE(n > 0);
            done += static_cast<size_t>(n);
        }
    }
    void line(const std::string& csv) { send(with_checksum(csv) + "\n"); }
    // Reads what the logger sent for up to `ms`; true once a "hello" line has arrived.
    bool heard_hello(int ms) {
        const auto until = Clock::now() + std::chrono::milliseconds(ms);
        while (Clock::now() < until) {
            pollfd p{master_, POLLIN, 0};
            if (::poll(&p, 1, 20) > 0 && (p.revents & POLLIN)) {
                char buf[256];
                const ssize_t n = ::read(master_, buf, sizeof buf);
                if (n > 0) input_.append(buf, static_cast<size_t>(n));
            }
            const size_t at = input_.find("hello\n");
            if (at != std::string::npos) {
                input_.erase(0, at + 6);
                return true;
            }
        }
        return false;
    }
    // A device waiting for its host: "BMS" until greeted, then "hello" (and the header next).
    void await_greeting() {
        bool greeted = false;
        for (int i = 0; i < 100 && !greeted; ++i) {
            send("BMS\r\n");
            greeted = heard_hello(100);
        }
        REQUIRE(greeted);
        send("hello\r\n");
    }
    void handshake(const std::string& header) {
        await_greeting();
        line(header);
    }

private:
    std::string link_;
    int master_ = -1;
    int slave_fd_ = -1;
    std::string input_;
};

std::string data_line(int i) { return std::to_string(629000 + 67000 * i) + ",16.66000," + std::to_string(i) + ".5"; }

// Waits until `path` holds at least `lines` lines.
bool wait_for_lines(const std::string& path, long lines, int ms = 10000) {
    const auto until = Clock::now() + std::chrono::milliseconds(ms);
    while (Clock::now() < until) {
        const std::string s = fwtest::read_file(path);
        if (std::count(s.begin(), s.end(), '\n') >= lines) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
}

SerialLogOptions options(const std::string& port, const std::string& out) {
    SerialLogOptions o;
    o.port = port;
    o.out_path = out;
    o.hello_interval_s = 0.2;
    o.reopen_interval_s = 0.05;
    o.fsync_interval_s = 0.1;
    return o;
}

const std::string kHeader = "time_us,voltage_v,current_a";

// Stops and joins a logger thread however the test leaves its scope, so a failed check
// ends the test instead of hanging it.
struct Joiner {
    std::atomic<bool>& stop;
    std::thread& thread;
    ~Joiner() {
        stop = true;
        if (thread.joinable()) thread.join();
    }
};

}  // namespace

TEST_CASE("serial logger: handshake, drop mid-line, return, device reset; every line once, none cut",
          "[serial]") {
    const std::string dir = fwtest::temp_dir("serial");
    const std::string link = dir + "/ttyBMS";
    const std::string out = dir + "/log.csv";
    FakeDevice dev(link);
    dev.plug();

    std::atomic<bool> stop{false};
    SerialLogStats stats;
    std::vector<std::string> messages;
    std::thread logger([&] {
        stats = run_serial_logger(options(link, out), stop, [&](const std::string& m) { messages.push_back(m); });
    });
    Joiner joiner{stop, logger};

    std::string expected = kHeader + "\n";
    int n = 0;
    // 1. A fresh device: prompts until greeted, then header and data, a note, a damaged line.
    dev.handshake(kHeader);
    for (; n < 40; ++n) {
        dev.line(data_line(n));
        expected += data_line(n) + "\n";
    }
    dev.send("# battery 1\n");
    std::string damaged = with_checksum(data_line(999));
    damaged[3] = damaged[3] == '0' ? '1' : '0';
    dev.send(damaged + "\n");
    REQUIRE(wait_for_lines(out, 41));
    // The link drops in the middle of a line.
    const std::string cut = with_checksum(data_line(40));
    dev.send(cut.substr(0, cut.size() / 2));
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    dev.unplug();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));

    // 2. The same device comes back still streaming: the rest of the cut line first (a
    // fragment), lines sent before the logger is there, then the greeting and more lines.
    dev.plug();
    dev.send(cut.substr(cut.size() / 2) + "\n");
    for (n = 41; n < 60; ++n) {
        dev.line(data_line(n));
        expected += data_line(n) + "\n";
    }
    REQUIRE(dev.heard_hello(3000));
    dev.send("hello\n");
    dev.line(kHeader);
    for (; n < 80; ++n) {
        dev.line(data_line(n));
        expected += data_line(n) + "\n";
    }
    REQUIRE(wait_for_lines(out, 1 + 79));
    dev.unplug();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));

    // 3. The device was reset: it prompts again and sends its header again.
    dev.plug();
    dev.handshake(kHeader);
    for (; n < 100; ++n) {
        dev.line(data_line(n));
        expected += data_line(n) + "\n";
    }
    REQUIRE(wait_for_lines(out, 1 + 99));
    stop = true;
    logger.join();

    CHECK(fwtest::read_file(out) == expected);  // line 40 (cut) absent, nothing twice, nothing partial
    CHECK(stats.lines_written == 99);
    CHECK(stats.header_written == 1);
    CHECK(stats.connections == 3);
    CHECK(stats.repeated_headers == 2);
    CHECK(stats.corrupt_lines >= 2);  // the damaged line and the fragment
    CHECK(stats.notes == 1);
    CHECK(stats.held_dropped == 0);
    CHECK(std::find(messages.begin(), messages.end(), "device: battery 1") != messages.end());
}

TEST_CASE("serial logger: a damaged header is asked for again, never taken from the next data row", "[serial]") {
    // The header's checksum broken after hello: the next data row had become the new file's
    // first line (and, with --append or on a reconnect, stopped the run as a mismatch).
    const std::string dir = fwtest::temp_dir("serial-header");
    const std::string link = dir + "/ttyBMS";
    const std::string out = dir + "/log.csv";
    FakeDevice dev(link);
    dev.plug();
    std::atomic<bool> stop{false};
    SerialLogStats stats;
    std::thread logger([&] { stats = run_serial_logger(options(link, out), stop, [](const std::string&) {}); });
    Joiner joiner{stop, logger};

    dev.await_greeting();
    std::string bad = with_checksum(kHeader);
    bad[2] = bad[2] == 'm' ? 'n' : 'm';
    dev.send(bad + "\n");
    std::string expected = kHeader + "\n";
    for (int n = 0; n < 5; ++n) {
        dev.line(data_line(n));
        expected += data_line(n) + "\n";
    }
    REQUIRE(dev.heard_hello(3000));  // greeted again for the header
    dev.send("hello\r\n");
    dev.line(kHeader);
    for (int n = 5; n < 10; ++n) {
        dev.line(data_line(n));
        expected += data_line(n) + "\n";
    }
    REQUIRE(wait_for_lines(out, 11));
    stop = true;
    logger.join();
    CHECK(fwtest::read_file(out) == expected);  // the header first, the held rows kept
    CHECK(stats.corrupt_lines == 1);
}

TEST_CASE("serial logger: a device whose time restarts continues in the next part, each a file battsim reads",
          "[serial]") {
    // A NodeMCU powered by the USB link resets when the link drops: it comes back with its
    // clock and mAh count from zero. Written on, the file had a time that goes back there,
    // which every battsim command refuses ("time goes backwards").
    const std::string dir = fwtest::temp_dir("serial-restart");
    const std::string link = dir + "/ttyBMS";
    const std::string out = dir + "/log.csv";
    fwtest::write_file(dir + "/log-2.csv", "an earlier run's part\n");  // never written over
    FakeDevice dev(link);
    dev.plug();
    std::atomic<bool> stop{false};
    std::vector<std::string> messages;
    SerialLogStats stats;
    std::thread logger([&] {
        stats = run_serial_logger(options(link, out), stop, [&](const std::string& m) { messages.push_back(m); });
    });
    Joiner joiner{stop, logger};
    dev.handshake(kHeader);
    std::string first = kHeader + "\n";
    for (int n = 0; n < 10; ++n) {
        dev.line(data_line(n));
        first += data_line(n) + "\n";
    }
    REQUIRE(wait_for_lines(out, 11));
    dev.unplug();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    dev.plug();
    dev.handshake(kHeader);
    dev.line(data_line(0));  // its clock from zero again
    dev.line(data_line(1));
    REQUIRE(wait_for_lines(dir + "/log-3.csv", 3));
    stop = true;
    logger.join();
    CHECK(fwtest::read_file(out) == first);
    CHECK(fwtest::read_file(dir + "/log-2.csv") == "an earlier run's part\n");
    CHECK(fwtest::read_file(dir + "/log-3.csv") == kHeader + "\n" + data_line(0) + "\n" + data_line(1) + "\n");
    CHECK(stats.lines_written == 12);
    CHECK(stats.restarts == 1);
    CHECK(stats.files == std::vector<std::string>{out, dir + "/log-3.csv"});
    CHECK(std::find(messages.begin(), messages.end(),
                    "the device restarted (its time_us went back from 1232000 to 629000): its clock and counts start "
                    "again from zero, so the rest goes to " + dir + "/log-3.csv (" + out + " holds what came before)") !=
          messages.end());

    // --append to a file whose last time is later than the device's: the device restarted
    // between the runs, and its lines go to the next free part too.
    stop = false;
    std::thread again([&] {
        SerialLogOptions o = options(link, out);
        o.append = true;
        stats = run_serial_logger(o, stop);
    });
    Joiner joiner2{stop, again};
    dev.unplug();
    dev.plug();
    dev.handshake(kHeader);
    dev.line(data_line(2));
    REQUIRE(wait_for_lines(dir + "/log-4.csv", 2));
    stop = true;
    again.join();
    CHECK(fwtest::read_file(out) == first);
    CHECK(fwtest::read_file(dir + "/log-4.csv") == kHeader + "\n" + data_line(2) + "\n");
    CHECK(stats.files == std::vector<std::string>{out, dir + "/log-4.csv"});
}

TEST_CASE("serial logger: --append repairs a cut last line, refuses another device's header", "[serial]") {
    const std::string dir = fwtest::temp_dir("serial-append");
    const std::string link = dir + "/ttyBMS";
    const std::string out = dir + "/log.csv";
    fwtest::write_file(out, kHeader + "\n" + data_line(0) + "\n" + data_line(1).substr(0, 9));

    std::atomic<bool> stop{false};
    SerialLogOptions o = options(link, out);
    // Without --append an existing file is never touched.
    CHECK_THROWS_WITH(run_serial_logger(o, stop), Catch::Contains("already exists"));

    FakeDevice dev(link);
    dev.plug();
    o.append = true;
    SerialLogStats stats;
    std::thread logger([&] { stats = run_serial_logger(o, stop); });
    Joiner joiner{stop, logger};
    dev.handshake(kHeader);
    dev.line(data_line(2));
    REQUIRE(wait_for_lines(out, 3));
    stop = true;
    logger.join();
    CHECK(fwtest::read_file(out) == kHeader + "\n" + data_line(0) + "\n" + data_line(2) + "\n");
    CHECK(stats.repaired_tail);
    CHECK(stats.repeated_headers == 1);

    // A device with another header (another program, another cell count) is refused.
    stop = false;
    std::string error;
    std::thread second([&] {
        try {
            run_serial_logger(o, stop);
        } catch (const HeaderMismatch& e) {
            error = e.what();
        }
    });
    Joiner joiner2{stop, second};
    dev.unplug();
    dev.plug();
    dev.handshake("time_us,voltage_v,current_a,cell1_v");
    second.join();
    CHECK(error.find("differs from the file's") != std::string::npos);
    CHECK(fwtest::read_file(out) == kHeader + "\n" + data_line(0) + "\n" + data_line(2) + "\n");
}

TEST_CASE("serial logger: gives up after --max-wait when no device is there", "[serial]") {
    const std::string dir = fwtest::temp_dir("serial-wait");
    std::atomic<bool> stop{false};
    SerialLogOptions o = options(dir + "/nothing", dir + "/log.csv");
    o.max_wait_s = 0.3;
    const auto t0 = Clock::now();
    const SerialLogStats s = run_serial_logger(o, stop);
    const double took = std::chrono::duration<double>(Clock::now() - t0).count();
    CHECK(s.device_gone);
    CHECK(s.connections == 0);
    CHECK(took >= 0.3);
    CHECK(took < 3.0);
    o.baud = 12345;
    CHECK_THROWS_AS(run_serial_logger(o, stop), std::invalid_argument);
}

TEST_CASE("battsim log records a device end to end and stops after --max-wait", "[serial][cli]") {
    const std::string dir = fwtest::temp_dir("serial-cli");
    const std::string link = dir + "/ttyBMS";
    const std::string out = dir + "/log.csv";
    FakeDevice dev(link);
    dev.plug();
    fwtest::Run r;
    // `timeout` bounds the child even if this test goes wrong.
    std::thread cli([&] {
        r = fwtest::run("timeout", "20 " + fwtest::q(BATTSIM_BINARY) + " log --port " + fwtest::q(link) + " --out " +
                                       fwtest::q(out) + " --max-wait 0.5");
    });
    struct CliJoiner {
        std::thread& t;
        FakeDevice& d;
        ~CliJoiner() {
            d.unplug();
            if (t.joinable()) t.join();
        }
    } cli_joiner{cli, dev};
    dev.handshake(kHeader);
    std::string expected = kHeader + "\n";
    for (int i = 0; i < 25; ++i) {
        dev.line(data_line(i));
        expected += data_line(i) + "\n";
    }
    REQUIRE(wait_for_lines(out, 26));
    // Reset: back within --max-wait, its clock from zero; the rest goes to the next part.
    dev.unplug();
    dev.plug();
    dev.handshake(kHeader);
    dev.line(data_line(0));
    REQUIRE(wait_for_lines(dir + "/log-2.csv", 2));
    dev.send("$half,a,li");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    dev.unplug();
    cli.join();
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(fwtest::read_file(out) == expected);
    CHECK(fwtest::read_file(dir + "/log-2.csv") == kHeader + "\n" + data_line(0) + "\n");
    CHECK(r.err.find("26 lines written to " + out + " and " + dir + "/log-2.csv (") != std::string::npos);
    CHECK(r.err.find(", 1 device restart)") != std::string::npos);

    // A port that never appears is an input error.
    r = fwtest::run(BATTSIM_BINARY, "log --port " + fwtest::q(dir + "/none") + " --out " + fwtest::q(dir + "/b.csv") +
                                        " --max-wait 0.2 -q");
    CHECK(r.exit_code == 3);
    r = fwtest::run(BATTSIM_BINARY, "log --port " + fwtest::q(dir + "/none") + " --out " + fwtest::q(dir + "/c.csv") +
                                        " --max-wait 0.2");
    CHECK(r.err.find("none has been gone for 0.2 s; stopping") != std::string::npos);  // not "0.200000 s"
    r = fwtest::run(BATTSIM_BINARY, "log --port " + fwtest::q(link) + " --out " + fwtest::q(out) + " --max-wait 0.2");
    CHECK(r.exit_code == 5);  // exists, no --append
    CHECK(r.err.find("already exists") != std::string::npos);
}
