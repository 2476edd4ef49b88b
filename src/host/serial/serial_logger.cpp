#include "host/serial/serial_logger.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <thread>
#include <vector>

#include "host/serial/line_protocol.h"
#include "host/serial/serial_port.h"

namespace battsim {
namespace host {
namespace serial {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string errno_text() { return std::strerror(errno); }

// The n-th part of a recording: "flight.csv" -> "flight-2.csv" (the extension of the file
// name kept; none: "-2" appended).
std::string part_path(const std::string& path, int n) {
    const std::string::size_type slash = path.rfind('/');
    const std::string::size_type dot = path.rfind('.');
    const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
    const std::string stem = has_ext ? path.substr(0, dot) : path;
    return stem + "-" + std::to_string(n) + (has_ext ? path.substr(dot) : "");
}

// The output: grows only by whole lines, one write() each, on an O_APPEND descriptor.
class LineFile {
public:
    LineFile(const std::string& path, bool append, bool& repaired) : path_(path) {
        struct stat st;
        const bool exists = ::stat(path.c_str(), &st) == 0;
        if (exists && !append && st.st_size > 0) {
            throw std::runtime_error(path + ": already exists; pass --append to continue it or choose another file");
        }
        fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
        if (fd_ < 0) throw std::runtime_error(path + ": cannot open for writing: " + errno_text());
        created_ = !exists;
        if (exists && st.st_size > 0) load_existing(repaired);
    }
    // A file this run created and never wrote (the port was no serial device, or it never
    // appeared) is removed: an empty --out would read as a log of a flight with no samples.
    ~LineFile() {
        if (fd_ < 0) return;
        struct stat st;
        const bool empty = ::fstat(fd_, &st) == 0 && S_ISREG(st.st_mode) && st.st_size == 0;
        ::close(fd_);
        if (created_ && empty) ::unlink(path_.c_str());
    }
    LineFile(const LineFile&) = delete;
    LineFile& operator=(const LineFile&) = delete;

    const std::string& header() const { return header_; }
    const std::string& path() const { return path_; }
    // The last line's text as found by --append ("" when the file had no data line).
    const std::string& last_existing_line() const { return last_line_; }

    void write_header(const std::string& h) {
        append_line(h);
        header_ = h;
    }
    void append_line(const std::string& text) {
        std::string line = text;
        line += '\n';
        const ssize_t n = ::write(fd_, line.data(), line.size());
        if (n != static_cast<ssize_t>(line.size())) {
            const std::string why = n < 0 ? errno_text() : "short write";
            // A short write on a full disk could leave part of a line: cut it off again.
            if (n > 0) truncate_to_last_newline();
            throw std::runtime_error(path_ + ": write failed: " + why);
        }
        dirty_ = true;
    }
    void sync() {
        if (!dirty_) return;
        if (::fsync(fd_) != 0) throw std::runtime_error(path_ + ": fsync failed: " + errno_text());
        dirty_ = false;
        last_sync_ = Clock::now();
    }
    void sync_if_due(double interval_s) {
        if (dirty_ && seconds_since(last_sync_) >= interval_s) sync();
    }

private:
    // Reads the header (first line) and removes a cut-off last line left by a crash.
    void load_existing(bool& repaired) {
        std::string content;
        char buf[65536];
        off_t pos = 0;
        for (;;) {
            const ssize_t n = ::pread(fd_, buf, sizeof buf, pos);
            if (n < 0) throw std::runtime_error(path_ + ": cannot read: " + errno_text());
            if (n == 0) break;
            content.append(buf, static_cast<size_t>(n));
            pos += n;
        }
        const std::string::size_type first_nl = content.find('\n');
        if (first_nl != std::string::npos) {
            header_ = content.substr(0, first_nl);
            if (!header_.empty() && header_.back() == '\r') header_.pop_back();
        }
        if (!content.empty() && content.back() != '\n') {
            truncate_to_last_newline();
            repaired = true;
            content.erase(content.rfind('\n') == std::string::npos ? 0 : content.rfind('\n') + 1);
        }
        // The last whole line after the header: a device that restarted since must not
        // continue this file with a time that goes back.
        if (first_nl != std::string::npos && content.size() > first_nl + 1) {
            const std::string::size_type end = content.size() - 1;  // its newline
            const std::string::size_type begin = content.rfind('\n', end - 1);
            if (begin != std::string::npos && begin >= first_nl && end > begin + 1)
                last_line_ = content.substr(begin + 1, end - begin - 1);
            if (!last_line_.empty() && last_line_.back() == '\r') last_line_.pop_back();
        }
    }
    void truncate_to_last_newline() {
        struct stat st;
        if (::fstat(fd_, &st) != 0) return;
        off_t end = st.st_size;
        char c = 0;
        while (end > 0) {
            if (::pread(fd_, &c, 1, end - 1) != 1) return;
            if (c == '\n') break;
            --end;
        }
        if (::ftruncate(fd_, end) != 0) throw std::runtime_error(path_ + ": cannot cut the unfinished last line: " + errno_text());
        if (end == 0) header_.clear();
    }

    std::string path_;
    int fd_ = -1;
    bool created_ = false;
    std::string header_;
    std::string last_line_;
    bool dirty_ = false;
    Clock::time_point last_sync_ = Clock::now();
};

class Session {
public:
    Session(const SerialLogOptions& o, const MessageSink& message, SerialLogStats& stats)
        : o_(o), message_(message), stats_(stats), file_(new LineFile(o.out_path, o.append, stats.repaired_tail)) {
        if (stats_.repaired_tail) say(o_.out_path + ": removed an unfinished last line left by an earlier run");
        stats_.files.push_back(o_.out_path);
        double t = 0.0;
        if (leading_number(file_->last_existing_line(), t)) {
            have_time_ = true;
            last_time_ = t;
        }
    }

    void run(const std::atomic<bool>& stop) {
        Clock::time_point absent_since = Clock::now();
        std::string bytes;
        std::vector<std::string> lines;
        bool reported_absent = false;
        while (!stop.load()) {
            if (!port_.is_open()) {
                if (!try_open()) {
                    if (!reported_absent) {
                        // Not there yet is the usual case (plugged in later); anything else
                        // (no permission) is said, as the user may have to act on it.
                        struct stat st;
                        say("waiting for " + o_.port +
                            (::stat(o_.port.c_str(), &st) == 0 ? " (" + open_error_ + ")" : " to appear (a serial device, tty)"));
                        reported_absent = true;
                    }
                    if (o_.max_wait_s > 0 && seconds_since(absent_since) >= o_.max_wait_s) {
                        stats_.device_gone = true;
                        char waited[32];  // as given: "0.5 s", not std::to_string's "0.500000 s"
                        std::snprintf(waited, sizeof waited, "%g", o_.max_wait_s);
                        say(o_.port + " has been gone for " + waited + " s; stopping");
                        break;
                    }
                    sleep_while_running(stop, o_.reopen_interval_s);
                    continue;
                }
                reported_absent = false;
            }
            bytes.clear();
            const SerialPort::Status st = port_.read(bytes, 100);
            if (st == SerialPort::Status::Gone) {
                lost_link();
                absent_since = Clock::now();
                continue;
            }
            if (!bytes.empty()) {
                lines.clear();
                splitter_.feed(bytes, lines);
                stats_.overlong_lines = splitter_.overlong();
                for (const std::string& l : lines) handle_line(l);
            }
            if (!confirmed_ && seconds_since(last_hello_) >= o_.hello_interval_s) {
                // A wrong baud rate or another firmware looks like a slow start: said now and
                // then, not only waited for.
                if (seconds_since(connected_at_) >= next_silence_note_s_) {
                    say("no header from " + o_.port + " after " + std::to_string(static_cast<int>(next_silence_note_s_)) +
                        " s of greeting it: is it the battsim firmware, at --baud " + std::to_string(o_.baud) + "?");
                    next_silence_note_s_ *= 2.0;
                }
                greet();
            }
            file_->sync_if_due(o_.fsync_interval_s);
        }
        // A clean stop: whatever is held without a confirmed header cannot be written, nor a
        // line still arriving.
        stats_.held_dropped += held_.size();
        if (splitter_.discard_partial() > 0) ++stats_.cut_lines;
        file_->sync();
    }

private:
    void say(const std::string& m) {
        if (message_) message_(m);
    }

    bool try_open() {
        try {
            port_.open(o_.port, o_.baud);
        } catch (const NotASerialDevice&) {
            throw;  // waiting would not make it one
        } catch (const SerialError& e) {
            open_error_ = e.what();
            const std::string prefix = o_.port + ": ";
            if (open_error_.compare(0, prefix.size(), prefix) == 0) open_error_.erase(0, prefix.size());
            return false;
        }
        ++stats_.connections;
        confirmed_ = false;
        expect_header_ = false;
        splitter_.discard_partial();
        connected_at_ = Clock::now();
        next_silence_note_s_ = 10.0;
        say("connected to " + o_.port);
        greet();
        return true;
    }

    void greet() {
        last_hello_ = Clock::now();
        port_.write("hello\n");
    }

    void lost_link() {
        port_.close();
        const size_t cut = splitter_.discard_partial();
        if (cut > 0) ++stats_.cut_lines;
        stats_.held_dropped += held_.size();
        held_.clear();
        confirmed_ = false;
        expect_header_ = false;
        file_->sync();
        say(o_.port + " disconnected" + (cut > 0 ? " mid-line (" + std::to_string(cut) + " bytes dropped)" : "") +
            "; waiting for it to come back");
    }

    void handle_line(const std::string& raw) {
        const DeviceLine d = classify_line(raw);
        switch (d.kind) {
            case LineKind::Prompt:
                // The device (re)started and waits: greet it, at most once per interval.
                confirmed_ = false;
                if (seconds_since(last_hello_) >= o_.hello_interval_s * 0.5) greet();
                return;
            case LineKind::Hello:
                expect_header_ = true;
                return;
            case LineKind::Note:
                ++stats_.notes;
                say("device: " + d.text);
                return;
            case LineKind::Corrupt:
                if (raw.empty()) return;
                ++stats_.corrupt_lines;
                // The header itself damaged: the next data row must not be taken for it (it had
                // become the new file's first line, or stopped an --append as a mismatch).
                // Greeted again, the device sends hello and its header again.
                if (expect_header_) {
                    expect_header_ = false;
                    greet();
                }
                return;
            case LineKind::Data:
                break;
        }
        if (expect_header_) {
            expect_header_ = false;
            // A header names columns; a row of numbers after hello is data (a header lost
            // whole): taken as data below, and the device greeted again.
            const bool number = !d.text.empty() && (std::isdigit(static_cast<unsigned char>(d.text[0])) || d.text[0] == '-');
            if (!number) {
                confirm_header(d.text);
                return;
            }
            greet();
        }
        if (!confirmed_) {
            // Data before this connection's header: hold it (the header is on its way).
            if (held_.size() >= o_.max_held_lines) {
                held_.pop_front();
                ++stats_.held_dropped;
            }
            held_.push_back(d.text);
            return;
        }
        if (d.text == file_->header()) {
            ++stats_.repeated_headers;
            return;
        }
        append_data(d.text);
    }

    // The first field as a number, if it is one (the time: time_us, time_s).
    static bool leading_number(const std::string& line, double& out) {
        const size_t comma = line.find(',');
        const std::string field = line.substr(0, comma);
        if (field.empty()) return false;
        char* end = nullptr;
        out = std::strtod(field.c_str(), &end);
        return end == field.c_str() + field.size();
    }

    void append_data(const std::string& line) {
        double t = 0.0;
        if (leading_number(line, t)) {
            // A reset restarts the device's clock and counts: written on, the file would hold a
            // time that goes back, which every battsim command refuses; so the rest goes to
            // the next part (log-2.csv), each part a log battsim reads.
            if (have_time_ && t < last_time_) next_part(t);
            have_time_ = true;
            last_time_ = t;
        }
        file_->append_line(line);
        ++stats_.lines_written;
    }

    // Closes the current file and continues in the first free "<stem>-N<ext>", N from 2,
    // with the same header.
    void next_part(double t) {
        file_->sync();
        const std::string header = file_->header();
        const std::string col = header.substr(0, header.find(','));
        const std::string from = file_->path();
        std::string path;
        for (int n = 2;; ++n) {
            path = part_path(o_.out_path, n);
            struct stat st;
            if (::stat(path.c_str(), &st) != 0 || st.st_size == 0) break;
        }
        bool repaired = false;
        file_.reset();
        file_.reset(new LineFile(path, false, repaired));
        file_->write_header(header);
        stats_.files.push_back(path);
        ++stats_.restarts;
        say("the device restarted (its " + col + " went back from " + line_time(last_time_) + " to " + line_time(t) +
            "): its clock and counts start again from zero, so the rest goes to " + path + " (" + from +
            " holds what came before)");
    }

    static std::string line_time(double t) {
        char b[32];
        std::snprintf(b, sizeof b, "%.17g", t);
        return b;
    }

    void confirm_header(const std::string& h) {
        if (file_->header().empty()) {
            file_->write_header(h);
            stats_.header_written = 1;
        } else if (h == file_->header()) {
            ++stats_.repeated_headers;
        } else {
            throw HeaderMismatch(o_.out_path + ": the device's header \"" + h + "\" differs from the file's \"" +
                                 file_->header() + "\"; record to a new file");
        }
        confirmed_ = true;
        for (const std::string& l : held_) {
            if (l == file_->header()) continue;
            append_data(l);
        }
        held_.clear();
    }

    static void sleep_while_running(const std::atomic<bool>& stop, double seconds) {
        const auto until = Clock::now() + std::chrono::duration<double>(seconds);
        while (!stop.load() && Clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }

    const SerialLogOptions& o_;
    const MessageSink& message_;
    SerialLogStats& stats_;
    std::unique_ptr<LineFile> file_;  // the file being written: the next part after a device restart
    SerialPort port_;
    LineSplitter splitter_;
    std::string open_error_;  // why the port did not open last time
    std::deque<std::string> held_;
    bool confirmed_ = false;
    bool have_time_ = false;  // a data line with a numeric first field was written this run
    double last_time_ = 0.0;
    bool expect_header_ = false;
    Clock::time_point last_hello_ = Clock::now() - std::chrono::hours(1);
    Clock::time_point connected_at_ = Clock::now();
    double next_silence_note_s_ = 10.0;  // the next "no header after N s" note (doubling)
};

}  // namespace

SerialLogStats run_serial_logger(const SerialLogOptions& options, const std::atomic<bool>& stop,
                                 const MessageSink& message) {
    baud_constant(options.baud);  // a bad rate is a usage error, before any file is touched
    check_serial_device(options.port);  // likewise a port that is a file or a directory
    SerialLogStats stats;
    Session session(options, message, stats);
    session.run(stop);
    return stats;
}

}  // namespace serial
}  // namespace host
}  // namespace battsim
