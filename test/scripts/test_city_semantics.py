#!/usr/bin/python3
"""The outside-judge re-verification of test_scenario_semantics.py (relations recomputed from
the JSON alone, confusers, priors, bands, vignettes, mutations detected) on a batch of 45
scenarios generated in the city world (hameritt_generate --world city), where the related
entities include the city classes (building, parking_garage, lamp_post, street_tree, ...).
Prints "N passed, M failed"; exits 1 on any failure or when fewer than 300 checks ran.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_scenario_semantics  # noqa: E402

if __name__ == "__main__":
    sys.exit(test_scenario_semantics.main(world="city", count=45, min_checks=300))
