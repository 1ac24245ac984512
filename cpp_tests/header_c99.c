/* Compiled as C99 with -pedantic -Werror: include/sddpm.h must be valid C. */
#include "sddpm.h"

int sddpm_header_c99_probe(void) {
  sddpm_mesh *mesh = NULL;
  sddpm_mesh_report report;
  sddpm_load_options opts;
  sddpm_progress_cb cb = NULL;
  sddpm_options *options = NULL;
  double level = 0;
  sddpm_status s = sddpm_load_options_default(&opts);
  (void)cb;
  (void)report;
  if (s == SDDPM_STATUS_OK) s = sddpm_mesh_load("", &opts, &mesh);
  if (s == SDDPM_STATUS_OK) s = sddpm_options_new(&options);
  if (s == SDDPM_STATUS_OK) s = sddpm_options_set_number(options, "hex.map.level", 2);
  if (s == SDDPM_STATUS_OK) s = sddpm_options_set_bool(options, "hex.quality.pillow", false);
  if (s == SDDPM_STATUS_OK) s = sddpm_options_get_number(options, "hex.map.level", &level);
  sddpm_options_free(options);
  sddpm_mesh_free(mesh);
  return (int)s + SDDPM_ABI_VERSION;
}
