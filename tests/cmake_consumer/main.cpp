// The installed C++ header: the same check through sddpm.hpp.
#include <iostream>
#include "sddpm.hpp"

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  try {
    auto m = sddpm::Mesh::load(argv[1]);
    std::cout << "genus " << m.genus() << "\n";
    return m.genus() == 1 ? 0 : 1;
  } catch (const sddpm::Error& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
}
