// Outputs are written to a temporary file beside the target and renamed into place on
// commit, so a crash or a bad input never leaves a half-written file behind. A temporary a
// killed process left (SIGKILL) is removed by the next write to the same target.
#pragma once
#include <cstdio>
#include <string>

namespace battsim {
namespace host {

// Whether `name` (a file name, no directory) is shaped like the temporaries AtomicFile writes
// (<target>.tmp.<pid>.<n>): one a killed writer left behind, a half-written output.
bool is_temporary_name(const std::string& name);

class AtomicFile {
public:
    // A symlink is followed: the temporary goes beside the file it points to, which the commit
    // replaces, so the link stays. An existing target that is not a regular file (a terminal,
    // /dev/null, a FIFO) is written straight, without a temporary: it cannot be renamed over.
    // "-" is standard output, written straight too.
    // An existing target's permissions carry over to the file that replaces it; a hard link
    // to the old file keeps the old contents (the rename gives the name a new file).
    explicit AtomicFile(const std::string& path);  // throws std::runtime_error if it cannot create
    ~AtomicFile();                                 // discards the temporary if not committed
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::FILE* handle() { return file_; }
    // Another program (e.g. gnuplot) may write the temporary by this name instead of
    // handle(); commit() then syncs and renames whatever it wrote. Written straight, the
    // output's own name.
    const std::string& temp_path() const { return temp_path_; }
    void write(const std::string& text);
    void write(const char* data, size_t size);
    void commit();  // flush, fsync, rename; throws std::runtime_error on failure
    const std::string& path() const { return path_; }
    bool direct() const { return direct_; }  // written straight (a device, a FIFO, "-")

private:
    std::string path_;
    std::string target_;  // path_ with its symlinks followed: what the commit replaces
    std::string temp_path_;
    std::FILE* file_ = nullptr;
    bool direct_ = false;  // a device or FIFO: no temporary, no rename
    bool stdout_ = false;  // "-": never closed here
    int temp_slot_ = -1;   // in the registry the signal handler cleans, -1 = not in it
    int lock_fd_ = -1;     // holds the temporary's flock() until it is renamed or removed
    bool committed_ = false;
};

// A scratch file of this process that is no output (gnuplot's messages): made empty, with a
// name of its own, in the temporary directory ($TMPDIR, else /tmp); removed by the
// destructor, or by the handler of install_temp_cleanup_on_signals when a signal comes first.
class ScratchFile {
public:
    explicit ScratchFile(const std::string& prefix);  // throws std::runtime_error if it cannot create
    ~ScratchFile();
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;
    const std::string& path() const { return path_; }

private:
    std::string path_;
    int slot_ = -1;
};

// Writes `text` to `path` atomically ("-" = standard output).
void write_file_atomic(const std::string& path, const std::string& text);

// `path` with the symlinks of its last component followed (a dangling link gives the file it
// would create): the file a write replaces. Throws std::runtime_error on a loop of links.
std::string resolve_output_path(const std::string& path);

// Installs SIGINT, SIGTERM, SIGHUP, SIGQUIT and SIGPIPE handlers (once; a signal already
// ignored stays ignored) that
// remove the temporaries of the AtomicFiles still open and the ScratchFiles, then die of the
// same signal.
void install_temp_cleanup_on_signals();

}  // namespace host
}  // namespace battsim
