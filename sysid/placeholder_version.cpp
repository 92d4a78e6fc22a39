// Keeps mppi_sysid a real library while its first sources land; removed once they do.
namespace mppi::sysid_detail {
int library_version() { return 1; }
}  // namespace mppi::sysid_detail
