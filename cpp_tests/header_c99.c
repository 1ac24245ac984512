/* Compiled as C99 with -pedantic -Werror: include/sddpm.h must be valid C. */
#include "sddpm.h"

int sddpm_header_c99_probe(void) {
  sddpm_mesh *mesh = NULL;
  sddpm_mesh_report report;
  sddpm_load_options opts;
  sddpm_progress_cb cb = NULL;
  sddpm_status s = sddpm_load_options_default(&opts);
  (void)cb;
  (void)report;
  if (s == SDDPM_STATUS_OK) s = sddpm_mesh_load("", &opts, &mesh);
  sddpm_mesh_free(mesh);
  return (int)s + SDDPM_ABI_VERSION;
}
