#!/bin/sh
# Stands in for a gtest binary: prints a --gtest_list_tests listing with a plain suite, a suite
# whose tests are all e2e, one mixing both, and parametrised and typed suites.
cat <<'LIST'
Plain.
  One
  Two
Loop.
  LongA
  LongB
Mixed.
  Fast
  Slow
Angles/Cone.
  Reads/0  # GetParam() = 25
  Reads/1  # GetParam() = 35
Typed/0.  # TypeParam = float
  Works
LIST
