#include "host/io/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <vector>
#include <random>
#include <stdexcept>

namespace battsim {
namespace host {

namespace fs = std::filesystem;

namespace {
// The name beside a target whose own name is near the file system's limit (255 bytes)
// is cut, or a name the user may create could not be written.
constexpr size_t kNameMax = 255;

std::string temp_name(const std::string& path) {
    // Unique per process and per call, so parallel writers never share a temporary.
    static std::atomic<unsigned> counter{0};
    const std::string suffix = ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    const size_t slash = path.rfind('/');
    const size_t name_start = slash == std::string::npos ? 0 : slash + 1;
    const size_t name_size = path.size() - name_start;
    if (name_size + suffix.size() <= kNameMax) return path + suffix;
    return path.substr(0, name_start + kNameMax - suffix.size()) + suffix;
}

// Stale temporaries. A signal the handler below catches removes the temporaries, but SIGKILL
// (`timeout -s KILL`, the OOM killer) and a power cut leave theirs beside the target, and
// every such run added one more. So a write to a target first removes the temporaries
// beside it that temp_name() made for that same target in a process that has died.
// O_TMPFILE + linkat() would leave no name to clean, but the temporary must have a name
// (gnuplot writes it by temp_path()), linkat() cannot replace an existing target (a named
// step and its rename were needed anyway), and not every file system has O_TMPFILE (NFS).
//
// A file is removed only when all of these hold, so nothing of anyone else's goes:
//  * its name is exactly <target name>.tmp.<pid>.<n> as temp_name() writes it (decimal, no
//    sign or leading zero; <target name> cut only as temp_name() cuts it);
//  * kill(<pid>, 0) fails with ESRCH (EPERM: alive, another user's), or /proc shows a zombie,
//    before and after the lock;
//  * it is a regular file (not a link) owned by this user, and no one holds the flock()
//    every writer takes on its temporary: a writer alive in another PID namespace (a
//    container) or on another host over NFS has a PID kill() cannot see, but holds that lock
//    until it exits, however it dies;
//  * the name still names the file that was locked when it is unlinked.
// Writers create their temporaries with O_EXCL, so a process that took a dead one's PID
// never writes into a file being removed.

// The PID in `entry` when its name ends as temp_name()'s temporaries do (".tmp.<pid>.<n>"),
// with the size of what comes before that; 0 if not.
pid_t temp_tail(const std::string& entry, size_t& prefix_size) {
    // Trailing "<digits>" (the count), then ".<digits>" (the PID), then ".tmp.".
    const auto digits_before = [&entry](size_t end, size_t& begin) {
        begin = end;
        while (begin > 0 && entry[begin - 1] >= '0' && entry[begin - 1] <= '9') --begin;
        const size_t n = end - begin;
        // as std::to_string writes them: no leading zero
        return n >= 1 && n <= 10 && (n == 1 || entry[begin] != '0');
    };
    size_t count_begin = 0, pid_begin = 0;
    if (!digits_before(entry.size(), count_begin) || count_begin == 0 || entry[count_begin - 1] != '.') return 0;
    if (!digits_before(count_begin - 1, pid_begin)) return 0;
    static const std::string kTag = ".tmp.";
    if (pid_begin < kTag.size() || entry.compare(pid_begin - kTag.size(), kTag.size(), kTag) != 0) return 0;
    prefix_size = pid_begin - kTag.size();
    const long long pid = std::stoll(entry.substr(pid_begin, count_begin - 1 - pid_begin));
    // Never 0 or negative: kill() would ask about a whole process group.
    if (pid < 1 || pid > INT_MAX) return 0;
    return static_cast<pid_t>(pid);
}

}  // namespace

bool is_temporary_name(const std::string& name) {
    size_t prefix_size = 0;
    return temp_tail(name, prefix_size) != 0;
}

namespace {

// The PID in `entry` when it is one of temp_name()'s temporaries for the target named
// `name` (the last component of its path); 0 if not.
pid_t temp_owner(const std::string& entry, const std::string& name) {
    size_t prefix_size = 0;
    const pid_t pid = temp_tail(entry, prefix_size);
    if (pid == 0) return 0;
    const bool whole = prefix_size == name.size() && entry.compare(0, prefix_size, name) == 0;
    // temp_name() cuts a long name so that the temporary's is exactly kNameMax bytes.
    const bool cut = entry.size() == kNameMax && prefix_size > 0 && prefix_size < name.size() &&
                     name.compare(0, prefix_size, entry, 0, prefix_size) == 0;
    return whole || cut ? pid : 0;
}

// A zombie has closed its files and will write nothing more, but kill() still finds it until
// it is reaped, and its parent may be gone (`timeout -s KILL` kills itself too, leaving the
// child to an init that may reap late). Linux's /proc tells; elsewhere it is taken as alive.
bool zombie(pid_t pid) {
    char path[32];
    std::snprintf(path, sizeof path, "/proc/%d/stat", static_cast<int>(pid));
    std::FILE* f = std::fopen(path, "re");
    if (!f) return false;
    char buf[512];
    const size_t got = std::fread(buf, 1, sizeof buf - 1, f);
    std::fclose(f);
    buf[got] = '\0';
    // "pid (comm) S ...": the command may hold ") ", so the state follows the last ')'.
    const char* end = std::strrchr(buf, ')');
    return end && end[1] == ' ' && (end[2] == 'Z' || end[2] == 'X');
}

bool process_gone(pid_t pid) {
    if (pid <= 0) return false;
    if (::kill(pid, 0) != 0) return errno == ESRCH;
    return zombie(pid);
}

// Each directory is listed once per process: the names in it shaped like a temporary. A
// batch writing thousands of summaries into one directory had listed it for every one
// (20,000 files: 4 ms a summary). A temporary left there later, by a writer that died while
// this process ran, goes with the next process's writes.
std::mutex g_candidates_lock;
std::map<std::string, std::vector<std::string>> g_candidates;  // directory -> names shaped like temporaries

// Best effort: whatever cannot be read, opened or locked is left as it is.
void remove_stale_temps(const std::string& target) {
    const size_t slash = target.rfind('/');
    const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : target.substr(0, slash);
    const std::string name = slash == std::string::npos ? target : target.substr(slash + 1);
    if (name.empty()) return;
    std::lock_guard<std::mutex> hold(g_candidates_lock);
    auto listed = g_candidates.find(dir);
    if (listed == g_candidates.end()) {
        std::vector<std::string> shaped;
        if (DIR* d = ::opendir(dir.c_str())) {
            size_t prefix_size = 0;
            while (const struct dirent* e = ::readdir(d))
                if (temp_tail(e->d_name, prefix_size) != 0) shaped.emplace_back(e->d_name);
            ::closedir(d);
        }
        listed = g_candidates.emplace(dir, std::move(shaped)).first;
    }
    std::vector<std::string>& candidates = listed->second;
    const pid_t self = ::getpid();
    DIR* d = nullptr;
    int dfd = -1;
    for (size_t k = 0; k < candidates.size();) {
        const std::string& entry = candidates[k];
        const pid_t pid = temp_owner(entry, name);
        if (pid == 0 || pid == self || !process_gone(pid)) {
            ++k;
            continue;
        }
        if (!d && !(d = ::opendir(dir.c_str()))) return;
        dfd = ::dirfd(d);
        bool removed = false;
        // Nothing but a regular file is opened (opening a device may act on it).
        struct stat named {};
        if (::fstatat(dfd, entry.c_str(), &named, AT_SYMLINK_NOFOLLOW) == 0 && S_ISREG(named.st_mode)) {
            // Read-write where allowed: over NFS an exclusive flock() needs a file open for writing.
            int fd = ::openat(dfd, entry.c_str(), O_RDWR | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
            if (fd < 0) fd = ::openat(dfd, entry.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
            if (fd >= 0) {
                struct stat locked {};
                if (::fstat(fd, &locked) == 0 && S_ISREG(locked.st_mode) && locked.st_uid == ::geteuid() &&
                    ::flock(fd, LOCK_EX | LOCK_NB) == 0 && process_gone(pid) &&
                    ::fstatat(dfd, entry.c_str(), &named, AT_SYMLINK_NOFOLLOW) == 0 && named.st_dev == locked.st_dev &&
                    named.st_ino == locked.st_ino)
                    removed = ::unlinkat(dfd, entry.c_str(), 0) == 0;
                ::close(fd);  // releases the lock
            }
        }
        // A locked one (its writer alive where kill() cannot see) is asked again next time;
        // one gone, or no file of ours to remove, is not.
        if (removed || ::fstatat(dfd, entry.c_str(), &named, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(named.st_mode))
            candidates.erase(candidates.begin() + static_cast<std::ptrdiff_t>(k));
        else
            ++k;
    }
    if (d) ::closedir(d);
}

// The temporaries alive now, for the signal handler: it may neither lock nor allocate, so a
// fixed array it can walk. Each slot's version is odd while its path changes (a seqlock):
// the handler unlinks only a path it copied between two equal, even versions.
constexpr size_t kTempSlots = 128;
constexpr size_t kTempPathMax = 4096;
struct TempSlot {
    std::atomic<bool> taken{false};
    std::atomic<unsigned> version{0};
    char path[kTempPathMax];
};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<unsigned>::is_always_lock_free,
              "the signal handler needs lock-free atomics");
TempSlot g_temps[kTempSlots];

// -1 when the path is too long or all slots are taken: that temporary is then removed only
// by its AtomicFile, as before.
int register_temp(const std::string& path) {
    if (path.size() >= kTempPathMax) return -1;
    for (size_t i = 0; i < kTempSlots; ++i) {
        bool expected = false;
        if (!g_temps[i].taken.compare_exchange_strong(expected, true)) continue;
        TempSlot& s = g_temps[i];
        s.version.fetch_add(1);
        std::memcpy(s.path, path.c_str(), path.size() + 1);
        s.version.fetch_add(1);
        return static_cast<int>(i);
    }
    return -1;
}

void unregister_temp(int slot) {
    if (slot < 0) return;
    TempSlot& s = g_temps[slot];
    s.version.fetch_add(1);
    s.path[0] = '\0';
    s.version.fetch_add(1);
    s.taken.store(false);
}

// Creations in flight, and whether a signal is cleaning up: the handler waits for the
// creations other threads have begun, so that no temporary is made after its sweep (with
// -j2, a worker's fopen could land after the main thread's sweep: 4 of 300 interrupted
// batches left an empty temporary). A creation begun after the sweep started never makes
// its file.
std::atomic<int> g_creating{0};
std::atomic<bool> g_cleaning{false};

class CreationGuard {
public:
    CreationGuard() {
        g_creating.fetch_add(1);
        if (g_cleaning.load()) {
            g_creating.fetch_sub(1);
            for (;;) ::pause();  // the process is about to die of the signal
        }
    }
    ~CreationGuard() { g_creating.fetch_sub(1); }
    CreationGuard(const CreationGuard&) = delete;
    CreationGuard& operator=(const CreationGuard&) = delete;
};

extern "C" void remove_temps_and_reraise(int sig) {
    const int saved_errno = errno;
    g_cleaning.store(true);
    // Bounded: the signal may have come to a thread inside its own creation.
    for (int waited_ms = 0; g_creating.load() > 0 && waited_ms < 200; ++waited_ms) {
        struct timespec ms {0, 1000000};
        ::nanosleep(&ms, nullptr);
    }
    for (TempSlot& s : g_temps) {
        if (!s.taken.load()) continue;
        const unsigned before = s.version.load();
        if (before & 1u) continue;
        char copy[kTempPathMax];
        std::memcpy(copy, s.path, sizeof copy);
        std::atomic_thread_fence(std::memory_order_acquire);
        if (s.version.load() != before || copy[0] == '\0') continue;
        copy[kTempPathMax - 1] = '\0';
        ::unlink(copy);
    }
    // Die of the same signal, so the parent sees how the run ended; it is delivered when
    // this handler returns.
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    errno = saved_errno;
}
}  // namespace

std::string resolve_output_path(const std::string& path) {
    fs::path p(path);
    for (int hop = 0;; ++hop) {
        std::error_code ec;
        if (!fs::is_symlink(fs::symlink_status(p, ec))) break;
        if (hop == 40) throw std::runtime_error(path + ": too many levels of symbolic links");
        const fs::path to = fs::read_symlink(p, ec);
        if (ec) break;
        p = to.is_absolute() ? to : p.parent_path() / to;
    }
    return p.string();
}

void install_temp_cleanup_on_signals() {
    static std::once_flag once;
    std::call_once(once, [] {
        // SIGPIPE: a reader of standard output gone (`| head`); SIGHUP: the terminal closed.
        for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE}) {
            struct sigaction old {};
            if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
            struct sigaction act {};
            act.sa_handler = remove_temps_and_reraise;
            sigemptyset(&act.sa_mask);
            ::sigaction(sig, &act, nullptr);
        }
    });
}

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
    if (path == "-") {
        direct_ = stdout_ = true;
        target_ = temp_path_ = path;
        file_ = stdout;
        return;
    }
    struct stat given {};
    const bool exists = ::stat(path.c_str(), &given) == 0;
    if (exists && S_ISDIR(given.st_mode)) throw std::runtime_error(path + ": cannot create output (is a directory)");
    direct_ = exists && !S_ISREG(given.st_mode);
    if (!direct_) {
        target_ = resolve_output_path(path);
        // A link whose text names no file the kernel reaches (/proc/self/fd/N of a deleted
        // file): write through the name itself.
        struct stat resolved {};
        if (exists && (::stat(target_.c_str(), &resolved) != 0 || resolved.st_dev != given.st_dev ||
                       resolved.st_ino != given.st_ino))
            direct_ = true;
    }
    if (!direct_) remove_stale_temps(target_);
    CreationGuard creating;
    if (direct_) {
        target_ = temp_path_ = path;
        file_ = std::fopen(temp_path_.c_str(), "wb");
    } else {
        // O_EXCL: a file already by that name (a dead process's of the same PID) is never
        // written into, so remove_stale_temps() cannot take a live temporary for it.
        for (int attempt = 0; attempt < 100 && !file_; ++attempt) {
            temp_path_ = temp_name(target_);
            // Registered before it exists, so no moment has it on disk unknown to the handler.
            temp_slot_ = register_temp(temp_path_);
            const int fd = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
            if (fd >= 0) {
                file_ = ::fdopen(fd, "wb");
                if (!file_) {
                    const int err = errno;
                    ::close(fd);
                    ::unlink(temp_path_.c_str());
                    errno = err;
                }
            }
            if (file_) break;
            const int err = errno;
            unregister_temp(temp_slot_);
            temp_slot_ = -1;
            errno = err;
            if (err != EEXIST) break;
        }
    }
    if (!file_) {
        const int err = errno;
        throw std::runtime_error(path + ": cannot create output (" + std::strerror(err) + ")");
    }
    if (!direct_) {
        // Held until the temporary is renamed or removed (a duplicate, so it outlives the
        // fclose() before the rename), and released by the kernel however this process
        // dies: remove_stale_temps() of another process leaves a locked temporary alone.
        lock_fd_ = ::fcntl(::fileno(file_), F_DUPFD_CLOEXEC, 0);
        if (lock_fd_ >= 0) (void)::flock(lock_fd_, LOCK_EX | LOCK_NB);
    }
    // The file it replaces keeps its permissions (a config made private stays private).
    struct stat old_target {};
    if (!direct_ && exists && ::stat(target_.c_str(), &old_target) == 0)
        (void)::fchmod(::fileno(file_), old_target.st_mode & 0777);  // not set-user-ID and kin
}

AtomicFile::~AtomicFile() {
    if (file_ && !stdout_) std::fclose(file_);
    if (!committed_ && !direct_) std::remove(temp_path_.c_str());
    unregister_temp(temp_slot_);
    if (lock_fd_ >= 0) ::close(lock_fd_);
}

void AtomicFile::write(const std::string& text) { write(text.data(), text.size()); }

void AtomicFile::write(const char* data, size_t size) {
    if (size && std::fwrite(data, 1, size, file_) != size)
        throw std::runtime_error(path_ + ": write failed (" + std::strerror(errno) + ")");
}

void AtomicFile::commit() {
    if (direct_) {
        // A device or FIFO cannot be fsynced (EINVAL); what it took is all there is to check.
        const bool flushed = std::fflush(file_) == 0;
        const int err = errno;
        const bool closed = stdout_ || std::fclose(file_) == 0;
        file_ = nullptr;
        if (!flushed || !closed) throw std::runtime_error(path_ + ": write failed (" + std::strerror(flushed ? errno : err) + ")");
        committed_ = true;
        return;
    }
    if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0) {
        throw std::runtime_error(path_ + ": write failed (" + std::strerror(errno) + ")");
    }
    std::fclose(file_);
    file_ = nullptr;
    if (std::rename(temp_path_.c_str(), target_.c_str()) != 0) {
        throw std::runtime_error(path_ + ": cannot move output into place (" + std::strerror(errno) + ")");
    }
    committed_ = true;
    unregister_temp(temp_slot_);
    temp_slot_ = -1;
    if (lock_fd_ >= 0) ::close(lock_fd_);
    lock_fd_ = -1;
}

ScratchFile::ScratchFile(const std::string& prefix) {
    std::error_code ec;
    fs::path dir = fs::temp_directory_path(ec);
    if (ec) dir = "/tmp";
    // A name nobody can guess, registered before it exists (as AtomicFile's temporaries), and
    // O_EXCL: a file of that name already there is someone else's and is never touched.
    static std::random_device entropy;
    static std::mutex entropy_lock;  // score's workers make scratch files at once
    static std::atomic<unsigned> counter{0};
    for (int attempt = 0; attempt < 100; ++attempt) {
        char tag[32];
        unsigned random_bits;
        {
            std::lock_guard<std::mutex> hold(entropy_lock);
            random_bits = entropy();
        }
        std::snprintf(tag, sizeof tag, "%d.%u.%08x", static_cast<int>(::getpid()), counter++, random_bits);
        const std::string path = (dir / (prefix + tag)).string();
        CreationGuard creating;
        const int slot = register_temp(path);
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (fd >= 0) {
            ::close(fd);
            path_ = path;
            slot_ = slot;
            return;
        }
        const int err = errno;
        unregister_temp(slot);
        if (err != EEXIST)
            throw std::runtime_error(path + ": cannot create a temporary file (" + std::strerror(err) + ")");
    }
    throw std::runtime_error(dir.string() + ": cannot create a temporary file (every name tried exists)");
}

ScratchFile::~ScratchFile() {
    ::unlink(path_.c_str());
    unregister_temp(slot_);
}

void write_file_atomic(const std::string& path, const std::string& text) {
    if (path == "-") {
        std::cout << text;
        std::cout.flush();
        return;
    }
    AtomicFile f(path);
    f.write(text);
    f.commit();
}

}  // namespace host
}  // namespace battsim
