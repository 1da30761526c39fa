"""Contingency policies in flight: the policy flown by a ground station in the loop
(``gcs-planner fly``) and its dry run against a live mock vehicle."""
