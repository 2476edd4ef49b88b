#include "host/serial/serial_port.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace battsim {
namespace host {
namespace serial {

unsigned baud_constant(unsigned baud) {
    switch (baud) {
        case 9600: return B9600;
        case 19200: return B19200;
        case 38400: return B38400;
        case 57600: return B57600;
        case 115200: return B115200;
        case 230400: return B230400;
        case 460800: return B460800;
        case 921600: return B921600;
        default: break;
    }
    throw std::invalid_argument("unsupported baud rate " + std::to_string(baud) +
                                " (expected 9600, 19200, 38400, 57600, 115200, 230400, 460800 or 921600)");
}

namespace {
const char* const kExpectedDevice = "; expected the serial port of the battsim firmware, e.g. /dev/ttyUSB0";
}  // namespace

void check_serial_device(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || S_ISCHR(st.st_mode)) return;
    const char* kind = S_ISREG(st.st_mode)    ? "a regular file"
                       : S_ISDIR(st.st_mode)  ? "a directory"
                       : S_ISFIFO(st.st_mode) ? "a FIFO"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                                              : "not a character device";
    throw NotASerialDevice(path + ": not a serial device (tty): it is " + kind + kExpectedDevice);
}

void SerialPort::open(const std::string& path, unsigned baud) {
    close();
    const speed_t speed = baud_constant(baud);
    check_serial_device(path);
    // O_NOCTTY: a logger must never become the device's controlling process.
    const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw SerialError(path + ": cannot open: " + std::strerror(errno));
    termios tio;
    if (::tcgetattr(fd, &tio) != 0) {
        const int err = errno;
        ::close(fd);
        if (err == ENOTTY)
            throw NotASerialDevice(path + ": not a serial device (tty): a character device that is no terminal" +
                                   kExpectedDevice);
        throw SerialError(path + ": not a serial device: " + std::strerror(err));
    }
    ::cfmakeraw(&tio);
    tio.c_cflag |= CLOCAL | CREAD;
    tio.c_cflag &= ~(CSTOPB | PARENB | CRTSCTS | HUPCL);
    tio.c_cflag = (tio.c_cflag & ~CSIZE) | CS8;
    tio.c_iflag &= ~(IXON | IXOFF | IXANY);
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 0;
    if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 || ::tcsetattr(fd, TCSANOW, &tio) != 0) {
        const int err = errno;
        ::close(fd);
        throw SerialError(path + ": cannot configure: " + std::strerror(err));
    }
    fd_ = fd;
}

void SerialPort::close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
}

SerialPort::Status SerialPort::read(std::string& out, int timeout_ms) {
    if (fd_ < 0) return Status::Gone;
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, timeout_ms);
    if (r < 0) return errno == EINTR ? Status::Timeout : Status::Gone;
    if (r == 0) return Status::Timeout;
    char buf[4096];
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n > 0) {
        out.append(buf, static_cast<size_t>(n));
        return Status::Data;
    }
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return Status::Timeout;
    // n == 0 with POLLIN/POLLHUP, or EIO: the device is gone (unplugged, pty closed).
    return Status::Gone;
}

bool SerialPort::write(const std::string& data) {
    size_t done = 0;
    int stalls = 0;
    while (done < data.size()) {
        if (fd_ < 0) return false;
        const ssize_t n = ::write(fd_, data.data() + done, data.size() - done);
        if (n > 0) {
            done += static_cast<size_t>(n);
            continue;
        }
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && errno == EAGAIN && ++stalls < 50) {
            pollfd p{fd_, POLLOUT, 0};
            ::poll(&p, 1, 20);
            continue;
        }
        return false;
    }
    return true;
}

}  // namespace serial
}  // namespace host
}  // namespace battsim
