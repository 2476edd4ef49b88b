// A command's outputs checked against its inputs and each other before it runs: an output
// naming an input destroys the input, and two outputs naming one file keep only the last.
#pragma once
#include <string>
#include <vector>

namespace battsim {
namespace host {

// What an output named "-" means. Only a text its writer can send to standard output takes
// it; for the others (binary streams, plots, directories, a log a device appends to) "-"
// would silently become a file of that name.
enum class Dash { Refused, StandardOutput };

struct NamedPath {
    std::string what;  // how the message names it: "--series", "the log"
    std::string path;  // "" and "-" (standard output) are never compared
    // An input config and an output config both marked may be one file: the config is read
    // whole before the run, and writing it back updated is the point (`--config-out PACK.json`).
    bool config = false;
    Dash dash = Dash::Refused;  // outputs only
    // An output directory the command makes when it is not there (batch --out): checked as
    // a directory, and the files listed inside it are not asked for a directory that exists.
    bool directory = false;
    // A file written in place, not replaced (`battsim log`): an existing one's own
    // permission counts, not its directory's.
    bool appended = false;
};

// Throws std::invalid_argument("--series and the log name the same file: X") when an output
// names the same file as an input or as an earlier output. Existing files are compared by
// identity (hard links and symlinks included), others by their resolved path; existing files
// that are not regular (devices, FIFOs) are never compared: writing one twice destroys nothing.
// An output "-" is refused unless it is Dash::StandardOutput, and so are two outputs on
// standard output, "-" or a name for it (names_standard_output); list a flag that prints
// to standard output, such as --json, as an output "-".
void check_output_paths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

// True for "-" and for a path that is standard output's file by another name (/dev/stdout,
// /proc/self/fd/1, or the file the shell redirected standard output to), unless that is a
// device such as /dev/null, which any number of writers may share.
bool names_standard_output(const std::string& path);

// Why a file cannot be written at `path` ("the directory /x does not exist", "no permission
// to write in /x"), "" when it can (or it is "-", a device, a FIFO). For commands whose run is
// long, checked before it, so a typo in -o does not throw the run away.
std::string unwritable_reason(const std::string& path);

// The same for a directory the command makes (with its parents) and writes files in: ""
// when it is one, or when the nearest existing one above it can be written in.
std::string unwritable_directory_reason(const std::string& path);

// The first output of `outputs` that cannot be written, with why ("" when all can): each file
// by unwritable_reason, unless it lies in one of the directory outputs; each directory by
// unwritable_directory_reason. `what` is set to the output's NamedPath::what.
std::string first_unwritable_output(const std::vector<NamedPath>& outputs, std::string* what, std::string* path);

// True when `a` and `b` name the same regular file, or the same file to be created.
bool same_output_file(const std::string& a, const std::string& b);

}  // namespace host
}  // namespace battsim
