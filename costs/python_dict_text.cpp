// Scanner of `'key': value` in Python-dict-like text (costs/python_dict_text.hpp).
#include "costs/python_dict_text.hpp"

#include <cstddef>

namespace mppi {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r'; }
bool is_quote(char c) { return c == '"' || c == '\''; }

}  // namespace

std::optional<std::string_view> python_dict_value(std::string_view text, std::string_view key) {
  constexpr auto npos = std::string_view::npos;
  const std::size_t n = text.size();
  // A list needs a ']' after its '['; past the last ']' of the text there is none, so the search
  // for one is never repeated in vain (which would make the scan quadratic).
  const std::size_t last_close = text.rfind(']');
  for (std::size_t q = text.find_first_of("\"'"); q != npos; q = text.find_first_of("\"'", q + 1)) {
    std::size_t i = q + 1;
    if (text.substr(i, key.size()) != key) continue;
    i += key.size();
    if (i >= n || !is_quote(text[i])) continue;
    ++i;
    while (i < n && is_space(text[i])) ++i;
    if (i >= n || text[i] != ':') continue;
    ++i;
    while (i < n && is_space(text[i])) ++i;
    if (i >= n) continue;
    if (text[i] == '[' && last_close != npos && last_close > i)
      return text.substr(i, text.find(']', i + 1) + 1 - i);
    std::size_t end = i;
    while (end < n && text[end] != ',' && text[end] != '}' && !is_space(text[end])) ++end;
    if (end > i) return text.substr(i, end - i);
  }
  return std::nullopt;
}

}  // namespace mppi
