// Planted for lint-nolint-selftest: four bad NOLINTs and one good one.
int a = 0; // NOLINT
int b = 0; // NOLINT(readability-magic-numbers): a check that is off
int c = 0; // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)
int d = 0; // NOLINT(*-avoid-non-const-global-variables): a wildcard
int e = 0; // NOLINT(cppcoreguidelines-avoid-non-const-global-variables): good, this one is allowed
