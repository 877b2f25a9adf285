// Planted for lint-nolint-selftest: the tests are not tidied, so a NOLINT here suppresses nothing.
int f = 0; // NOLINT(cppcoreguidelines-avoid-non-const-global-variables): in a test
