// NumPy .npz reader: libzip for the archive, a small hand-written parser for the .npy header.
// Every check is against the bytes actually read, so truncated or corrupt files end in an
// mppi::Error and never in an out-of-bounds read or a huge allocation.
#include "base/npz.hpp"

#include <zip.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string_view>

#include "base/error.hpp"

namespace mppi {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& why) { throw Error(path + ": " + why); }

std::string shape_string(const std::vector<std::size_t>& shape) {
  std::string s = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (i) s += ",";
    s += std::to_string(shape[i]);
  }
  return s + ")";
}

// ---- .npy header --------------------------------------------------------------------------
// The header is a Python dict literal, e.g. "{'descr': '<f8', 'fortran_order': False,
// 'shape': (32, 6), }". We look up the three keys numpy always writes; anything that does
// not fit this form (structured dtypes, odd spellings) is rejected.

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::size_t> shape;
};

class HeaderParser {
 public:
  HeaderParser(std::string_view text, const std::string& where) : text_(text), where_(where) {}

  NpyHeader parse() {
    NpyHeader h;
    h.descr = quoted_string_after(value_of("descr"));
    const std::size_t fo = value_of("fortran_order");
    if (text_.compare(fo, 4, "True") == 0) {
      h.fortran_order = true;
    } else if (text_.compare(fo, 5, "False") == 0) {
      h.fortran_order = false;
    } else {
      bad("'fortran_order' is neither True nor False");
    }
    h.shape = tuple_after(value_of("shape"));
    return h;
  }

 private:
  [[noreturn]] void bad(const std::string& why) const {
    throw Error(where_ + ": bad .npy header (" + why + "): " + std::string(text_.substr(0, 200)));
  }
  std::size_t skip_spaces(std::size_t p) const {
    while (p < text_.size() && (text_[p] == ' ' || text_[p] == '\t')) ++p;
    return p;
  }
  // Position of the first non-blank character after "'key':".
  std::size_t value_of(const std::string& key) const {
    std::size_t p = text_.find("'" + key + "'");
    if (p == std::string_view::npos) p = text_.find("\"" + key + "\"");
    if (p == std::string_view::npos) bad("no '" + key + "'");
    p = skip_spaces(p + key.size() + 2);
    if (p >= text_.size() || text_[p] != ':') bad("no ':' after '" + key + "'");
    return skip_spaces(p + 1);
  }
  std::string quoted_string_after(std::size_t p) const {
    if (p >= text_.size() || (text_[p] != '\'' && text_[p] != '"'))
      bad("'descr' is not a simple dtype string (structured dtypes are not supported)");
    const char quote = text_[p];
    const std::size_t end = text_.find(quote, p + 1);
    if (end == std::string_view::npos) bad("unterminated 'descr'");
    return std::string(text_.substr(p + 1, end - p - 1));
  }
  std::vector<std::size_t> tuple_after(std::size_t p) const {
    if (p >= text_.size() || text_[p] != '(') bad("'shape' is not a tuple");
    const std::size_t end = text_.find(')', p);
    if (end == std::string_view::npos) bad("unterminated 'shape'");
    std::vector<std::size_t> shape;
    std::size_t i = p + 1;
    while (true) {
      i = skip_spaces(i);
      if (i == end) break;
      std::size_t v = 0;
      const std::size_t digits_start = i;
      while (i < end && text_[i] >= '0' && text_[i] <= '9') {
        const std::size_t digit = static_cast<std::size_t>(text_[i] - '0');
        if (v > (std::numeric_limits<std::size_t>::max() - digit) / 10) bad("dimension too large");
        v = v * 10 + digit;
        ++i;
      }
      if (i == digits_start) bad("'shape' holds something other than integers");
      shape.push_back(v);
      i = skip_spaces(i);
      if (i < end && text_[i] == ',') ++i;
      else if (i != end) bad("'shape' holds something other than integers");
    }
    return shape;
  }

  std::string_view text_;
  const std::string& where_;
};

// ---- element conversion ---------------------------------------------------------------------

template <class T>
void convert(const unsigned char* src, std::size_t n, std::vector<double>& out) {
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    T v;
    std::memcpy(&v, src + i * sizeof(T), sizeof(T));  // no alignment assumption
    out[i] = static_cast<double>(v);
  }
}

// Element size for the dtypes we read; 0 if unsupported. Little-endian host assumed (x86/ARM).
std::size_t item_size(const std::string& descr) {
  if (descr == "<f8" || descr == "<i8") return 8;
  if (descr == "<f4" || descr == "<i4") return 4;
  if (descr == "|u1" || descr == "|b1") return 1;
  return 0;
}

NpyArray parse_npy(const std::vector<unsigned char>& bytes, const std::string& where) {
  static constexpr unsigned char kMagic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
  if (bytes.size() < 10 || std::memcmp(bytes.data(), kMagic, 6) != 0)
    throw Error(where + ": not a .npy array (bad magic)");
  const unsigned major = bytes[6];
  std::size_t header_len = 0, header_start = 0;
  if (major == 1) {
    header_len = bytes[8] | (static_cast<std::size_t>(bytes[9]) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw Error(where + ": truncated .npy header");
    header_len = bytes[8] | (static_cast<std::size_t>(bytes[9]) << 8) |
                 (static_cast<std::size_t>(bytes[10]) << 16) | (static_cast<std::size_t>(bytes[11]) << 24);
    header_start = 12;
  } else {
    throw Error(where + ": unsupported .npy format version " + std::to_string(major));
  }
  if (header_len > bytes.size() - header_start) throw Error(where + ": truncated .npy header");
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()) + header_start, header_len);
  const NpyHeader h = HeaderParser(text, where).parse();

  const std::size_t isize = item_size(h.descr);
  if (isize == 0)
    throw Error(where + ": unsupported dtype '" + h.descr +
                "' (supported: <f4 <f8 <i4 <i8 |u1 |b1, little-endian)");
  if (h.fortran_order)
    throw Error(where + ": Fortran-order arrays are not supported (save with np.ascontiguousarray)");

  std::size_t count = 1;
  for (std::size_t d : h.shape) {
    if (d != 0 && count > std::numeric_limits<std::size_t>::max() / isize / d)
      throw Error(where + ": shape " + shape_string(h.shape) + " is too large");
    count *= d;
  }
  const std::size_t data_bytes = bytes.size() - header_start - header_len;
  if (data_bytes != count * isize)
    throw Error(where + ": data holds " + std::to_string(data_bytes) + " bytes but shape " +
                shape_string(h.shape) + " of '" + h.descr + "' needs " + std::to_string(count * isize));

  NpyArray a;
  a.shape = h.shape;
  a.dtype = h.descr;
  const unsigned char* src = bytes.data() + header_start + header_len;
  if (h.descr == "<f8") convert<double>(src, count, a.values);
  else if (h.descr == "<f4") convert<float>(src, count, a.values);
  else if (h.descr == "<i8") convert<std::int64_t>(src, count, a.values);
  else if (h.descr == "<i4") convert<std::int32_t>(src, count, a.values);
  else convert<std::uint8_t>(src, count, a.values);  // |u1 and |b1 (numpy bools are 0/1 bytes)
  return a;
}

// ---- zip ------------------------------------------------------------------------------------

struct ZipCloser {
  void operator()(zip_t* z) const { zip_discard(z); }  // read-only: nothing to write back
};
struct ZipFileCloser {
  void operator()(zip_file_t* f) const { zip_fclose(f); }
};

std::vector<unsigned char> read_member(zip_t* zip, zip_uint64_t index, const std::string& where) {
  zip_stat_t st;
  zip_stat_init(&st);
  if (zip_stat_index(zip, index, 0, &st) != 0) throw Error(where + ": " + zip_strerror(zip));
  std::unique_ptr<zip_file_t, ZipFileCloser> file(zip_fopen_index(zip, index, 0));
  if (!file) throw Error(where + ": " + zip_strerror(zip));
  // Read in chunks rather than trusting the declared size for one big allocation: a corrupt
  // size field must not make us allocate gigabytes.
  std::vector<unsigned char> bytes;
  constexpr std::size_t kChunkBytes = 1 << 16;
  while (true) {
    const std::size_t old = bytes.size();
    bytes.resize(old + kChunkBytes);
    const zip_int64_t n = zip_fread(file.get(), bytes.data() + old, kChunkBytes);
    if (n < 0) throw Error(where + ": " + zip_file_strerror(file.get()));
    bytes.resize(old + static_cast<std::size_t>(n));
    if (n == 0) break;
  }
  if ((st.valid & ZIP_STAT_SIZE) && bytes.size() != st.size)
    throw Error(where + ": read " + std::to_string(bytes.size()) + " bytes, archive says " +
                std::to_string(st.size));
  return bytes;
}

}  // namespace

NpzFile NpzFile::load(const std::string& path) {
  int err = 0;
  std::unique_ptr<zip_t, ZipCloser> zip(zip_open(path.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &err));
  if (!zip) {
    zip_error_t ze;
    zip_error_init_with_code(&ze, err);
    const std::string why = zip_error_strerror(&ze);
    zip_error_fini(&ze);
    fail(path, "cannot read as a .npz (zip) archive: " + why);
  }
  NpzFile npz;
  npz.path_ = path;
  const zip_int64_t n = zip_get_num_entries(zip.get(), 0);
  if (n < 0) fail(path, zip_strerror(zip.get()));
  for (zip_int64_t i = 0; i < n; ++i) {
    const auto index = static_cast<zip_uint64_t>(i);
    const char* name_c = zip_get_name(zip.get(), index, 0);
    if (!name_c) fail(path, zip_strerror(zip.get()));
    const std::string name = name_c;
    // numpy stores array "k" as member "k.npy"; other members (none from np.savez) are skipped.
    if (name.size() < 4 || name.compare(name.size() - 4, 4, ".npy") != 0) continue;
    const std::string key = name.substr(0, name.size() - 4);
    const std::string where = path + ": array '" + key + "'";
    npz.arrays_[key] = parse_npy(read_member(zip.get(), index, where), where);
  }
  return npz;
}

std::vector<std::string> NpzFile::keys() const {
  std::vector<std::string> k;
  k.reserve(arrays_.size());
  for (const auto& [key, value] : arrays_) k.push_back(key);
  return k;
}

const NpyArray& NpzFile::at(const std::string& key) const {
  const auto it = arrays_.find(key);
  if (it == arrays_.end()) {
    std::string has;
    for (const auto& [k, v] : arrays_) has += (has.empty() ? "" : ", ") + k;
    fail(path_, "missing array '" + key + "' (has: " + (has.empty() ? "nothing" : has) + ")");
  }
  return it->second;
}

const NpyArray& NpzFile::at(const std::string& key, const std::vector<std::size_t>& expected_shape) const {
  const NpyArray& a = at(key);
  if (a.shape != expected_shape)
    fail(path_, "array '" + key + "' has shape " + shape_string(a.shape) + ", expected " +
                    shape_string(expected_shape));
  return a;
}

}  // namespace mppi
