// CSV-family sample readers: the header-less predictive-bms raw log and headered CSV
// with named columns. Both stream the file line by line (memory does not depend on the
// file length) and parse fields in place, without a std::string per line.
//
// Also exposes the small text helpers they are built from (field splitting, number
// parsing, message quoting), so the other text readers can report errors the same way.
#pragma once
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "host/io/sample_reader.h"

namespace battsim {
namespace host {

// Header-less predictive-bms log: time_ms, bus_voltage_v, cell1_v..cell4_v, current_ma,
// shunt_mv, normally with a trailing comma (9 fields, the last empty); 8 fields accepted.
// Current: CurrentSource::Auto/Current = logged current_ma / 1000; Shunt = recomputed
// from shunt_mv with options.shunt. Throws InputError (see the .cpp for the rules).
std::unique_ptr<SampleReader> open_raw_pbms(const std::string& path, const ReaderOptions& options);

// CSV with a header row. Columns come from options.columns; an empty entry uses the
// default names: time_s|time_ms|time_us, voltage_v, current_a|current_ma, cell1_v..cellN_v,
// temperature_c (a header with two of one quantity's names, time_s and time_ms, is refused
// unless that column is mapped). Units come from the scale fields, or else from the name suffix
// (time: _s/_ms/_us; current: _a/_ma; voltages: _mv means millivolts, anything else volts).
// CurrentSource::Shunt needs a shunt_mv column.
std::unique_ptr<SampleReader> open_csv(const std::string& path, const ReaderOptions& options);

namespace text {

// Result of parsing one field as a number.
enum class NumberStatus { Ok, Empty, NotANumber, NotFinite, OutOfRange };

// Parses the whole of `text` (already trimmed) as a decimal floating-point number,
// locale-independently. Accepts an optional leading '+'. NaN and infinities give
// NotFinite; anything left over after the number gives NotANumber.
NumberStatus parse_number(std::string_view text, double& out);

// Splits `line` at commas into views of `line` (cleared first; capacity is reused).
// Spaces and tabs around a field are dropped; a field in double quotes loses its
// quotes (a doubled "" inside stays doubled: use unquote() for names). Returns false
// and sets `bad_field` (1-based) if a quoted field is not closed or is followed by text.
bool split_fields(std::string_view line, std::vector<std::string_view>& fields, long& bad_field);

// 1-based field of `line` that byte `pos` falls in, counting commas outside quotes as
// split_fields() does (for messages about a byte inside a line).
long field_at(std::string_view line, std::size_t pos);

// Undoes the "" escape inside a field that split_fields() took out of quotes.
std::string unquote(std::string_view field);

// `text` in double quotes for a message, with control and non-ASCII bytes escaped and
// long text shortened.
std::string quote_for_message(std::string_view text);

// "expected a number, found \"abc\"" and friends, for a field that did not parse.
std::string number_error_message(NumberStatus status, std::string_view text);

}  // namespace text

}  // namespace host
}  // namespace battsim
