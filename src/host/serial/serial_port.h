// A serial device opened raw (termios: 8N1, no flow control, no line editing or echo),
// read with timeouts. Host only. A vanished device (USB unplugged, pty master closed)
// shows up as read() returning Status::Gone, never as an exception mid-stream.
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>

namespace battsim {
namespace host {
namespace serial {

class SerialError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// The path names something that is there but is no terminal (a file, a directory,
// /dev/null): it will not turn into the device, so waiting for it would wait forever.
class NotASerialDevice : public SerialError {
public:
    using SerialError::SerialError;
};

// Baud rates termios knows; throws std::invalid_argument for others.
unsigned baud_constant(unsigned baud);

// Throws NotASerialDevice when `path` exists and is not a character device. A missing path
// passes: the device may be plugged in later.
void check_serial_device(const std::string& path);

class SerialPort {
public:
    enum class Status { Data, Timeout, Gone };

    SerialPort() = default;
    ~SerialPort() { close(); }
    SerialPort(const SerialPort&) = delete;
    SerialPort& operator=(const SerialPort&) = delete;

    // Opens and configures `path`. Throws SerialError with the path and the reason,
    // NotASerialDevice for a path that is there but no terminal.
    // DTR/RTS are left as the driver sets them on open and HUPCL is cleared, so closing
    // the port does not pulse the NodeMCU's auto-reset lines.
    void open(const std::string& path, unsigned baud);
    void close();
    bool is_open() const { return fd_ >= 0; }

    // Waits up to timeout_ms for bytes; appends what arrived to `out`.
    Status read(std::string& out, int timeout_ms);
    // Writes all of `data`; false if the device went away.
    bool write(const std::string& data);

private:
    int fd_ = -1;
};

}  // namespace serial
}  // namespace host
}  // namespace battsim
