#pragma once
// The value text of one key in a Python-dict-like file (AutoRally's <track>.cfg), found by a
// hand-written scanner (costs/python_dict_text.cpp).
#include <optional>
#include <string_view>

namespace mppi {

// The raw value text of the first place in `text` that reads
//   Q key Q  ws  ':'  ws  value
// where each Q is ' or " (either one, independently), ws is any run (also empty) of space, \t,
// \n, \v, \f or \r, and value is
//   - a list: '[' up to and including the first ']' after it, or, where no ']' follows,
//   - a bare token: one or more characters up to the next ',', '}', whitespace or the end.
// A place where the key is not quoted on both sides, or no ':' or no value follows, does not
// count and the scan goes on after it: "x" is not found in "xBounds": [..], nor in "name": "x".
// The text is not parsed as a dict, though: the form above counts wherever it stands, also
// inside another key's string or list (AutoRally's files have no such text).
// The view points into `text`. Linear in the length of `text` (for a fixed key).
std::optional<std::string_view> python_dict_value(std::string_view text, std::string_view key);

}  // namespace mppi
