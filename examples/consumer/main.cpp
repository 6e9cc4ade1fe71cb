// Uses the installed dynahand package through its umbrella header: composes two poses and
// hashes the result.
#include <cstdio>

#include <dynahand/dynahand.h>

int main() {
  using namespace dynahand;
  const Pose a{Vec3(0.1f, 0.0f, 0.5f), Quat(Eigen::AngleAxisf(0.5f, Vec3::UnitY()))};
  const Pose b = a * a.inverse();
  Fnv1a hash;
  hash.add(b);
  std::printf("identity error %.2e, hash %016llx\n", static_cast<double>(b.p.norm()),
              static_cast<unsigned long long>(hash.value()));
  return b.p.norm() < 1e-6f ? 0 : 1;
}
