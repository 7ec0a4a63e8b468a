// The ctest fixture `surface_diagnosis` (FIXTURES_SETUP): empties the shared
// folder of the surface-diagnosis cases (surface_diagnosis_fixture.hpp) and
// writes the parts they machine, before any case runs.
#include <cstdio>
#include <exception>
#include <filesystem>

#include "surface_diagnosis_fixture.hpp"

int main() {
  namespace sf = truecut::analysis::test::surface_fixture;
  try {
    std::filesystem::remove_all(sf::root());
    const auto dir =
        sf::parts(truecut::sim::make_part(truecut::sim::PartId::kImplant, sf::part_options()));
    std::printf("%s\n", dir.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "surface_diagnosis fixture: %s\n", e.what());
    return 1;
  }
}
