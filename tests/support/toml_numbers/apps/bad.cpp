// A fixture for cmake/check_toml_numbers.cmake: a number read the way that loses large integers.
double fraction(const toml::table& t) { return *t["fraction"].value<double>(); }
