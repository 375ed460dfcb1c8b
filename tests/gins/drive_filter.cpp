// The one instance of run_drive for each layout (drive_filter.hpp).
#include "drive_filter.hpp"

namespace ctxfuse::test {

template DriveResult run_drive<Nav15>(const Drive&, const Nav15&, eskf::Belief<Nav15>&, const Constraints&, double, double,
                                      std::uint64_t);
template DriveResult run_drive<Nav20>(const Drive&, const Nav20&, eskf::Belief<Nav20>&, const Constraints&, double, double,
                                      std::uint64_t);

}  // namespace ctxfuse::test
