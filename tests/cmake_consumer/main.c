/* Loads a mesh through the installed C API; exits 0 only if its genus is 1. */
#include <stdio.h>
#include "sddpm.h"

int main(int argc, char **argv) {
  if (argc < 2) return 2;
  if (sddpm_abi_version() != SDDPM_ABI_VERSION) return 3;
  sddpm_mesh *m = NULL;
  sddpm_status s = sddpm_mesh_load(argv[1], NULL, &m);
  int64_t genus = -1;
  if (s == SDDPM_STATUS_OK) s = sddpm_mesh_genus(m, &genus);
  sddpm_mesh_free(m);
  printf("libsddpm %s: status %s, genus %lld\n", sddpm_version_string(), sddpm_status_name(s), (long long)genus);
  return (s == SDDPM_STATUS_OK && genus == 1) ? 0 : 1;
}
