// Fixture for the module_order_guard_rejects_upward_include test: cut may not include fem.
#include <incise/fem/elastic_problem.hpp>
