"""The one home of every setting: declarations (settings/*.yaml of each package) and what is made from
them (the C++ struct and visitor, dynamic_reconfigure's parameters, the README tables, the checks)."""
