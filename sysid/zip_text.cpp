#include "sysid/real_data.hpp"

#include <zip.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "base/error.hpp"

namespace mppi::sysid {

std::vector<std::string> zip_members(const std::string& zip_path) {
  int err = 0;
  zip_t* z = zip_open(zip_path.c_str(), ZIP_RDONLY, &err);
  if (!z) throw Error(zip_path + ": cannot open as a zip archive (libzip error " + std::to_string(err) + ")");
  std::vector<std::string> out;
  const zip_int64_t n = zip_get_num_entries(z, 0);
  for (zip_int64_t i = 0; i < n; ++i) out.emplace_back(zip_get_name(z, i, 0));
  zip_close(z);
  return out;
}

std::string read_text_or_zip_member(const std::string& spec) {
  const std::size_t zpos = spec.find(".zip:");
  if (zpos == std::string::npos) {
    std::ifstream in(spec, std::ios::binary);
    if (!in) throw Error(spec + ": cannot open");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  const std::string archive = spec.substr(0, zpos + 4), member = spec.substr(zpos + 5);
  int err = 0;
  std::unique_ptr<zip_t, int (*)(zip_t*)> z(zip_open(archive.c_str(), ZIP_RDONLY, &err), zip_close);
  if (!z) throw Error(archive + ": cannot open as a zip archive (libzip error " + std::to_string(err) + ")");
  zip_stat_t st;
  if (zip_stat(z.get(), member.c_str(), 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE)) {
    std::string names;
    for (const auto& m : zip_members(archive)) names += (names.empty() ? "" : ", ") + m;
    throw Error(archive + ": no member '" + member + "' (has: " + names + ")");
  }
  std::unique_ptr<zip_file_t, int (*)(zip_file_t*)> f(zip_fopen(z.get(), member.c_str(), 0), zip_fclose);
  if (!f) throw Error(spec + ": cannot open the member");
  std::string out(static_cast<std::size_t>(st.size), '\0');
  const zip_int64_t got = zip_fread(f.get(), out.data(), st.size);
  if (got != static_cast<zip_int64_t>(st.size)) throw Error(spec + ": truncated or corrupt member");
  return out;
}

}  // namespace mppi::sysid
