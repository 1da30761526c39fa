"""The paper's own routes, as printed, for re-evaluation by the project (section 4).

Source: Li, Ma & Pang, "Multi-Objective Path Optimization Method for Maritime UAVs Equipped with
Inertial Navigation Systems", J. Mar. Sci. Eng. 2025, 13(5), 870, Section 5.2:
Table 3 "Optimization results for the UAV path in Case 1" (dataset 1) and Table 4 "... in
Case 2" (dataset 2). (The page numbers did not survive the text extraction we read from,
../shared/paper/li-ma-pang-2025-jmse-13-870.txt.)

Each row is (calibration point number, vertical error before calibration, horizontal error before
calibration) as printed. In the extracted text the columns run together ("341719.97547.9646" is
row 3, point 417, 19.9754, 7.9646); every row was split so that both errors are within the
limits and each error equals the previous carried error plus the leg, and one row that still read
two ways (Table 4, row 16: point 16 or 161, both H points) was settled by the leg lengths: only
point 161 lies 9,081.1 m from point 302 and 10,146.4 m from B.

Mapping to the workbooks: the point number is the workbook's first column (编号), A is 0 and B
the last row's number (612 in dataset 1, 326 in dataset 2); ``Scenario.index_of(str(number))``
finds the row. The benchmark re-checks the printed errors against this mapping.
"""

from __future__ import annotations

# (point number, vertical error, horizontal error) on arrival, error units, A first, B last.
PaperRow = tuple[int, float, float]

TABLE3_DATASET1: tuple[PaperRow, ...] = (
    (0, 0.0, 0.0),
    (578, 12.0107, 12.0107),
    (417, 19.9754, 7.9646),
    (294, 5.3257, 13.2903),
    (91, 12.6804, 7.3547),
    (607, 8.3530, 15.7077),
    (61, 16.5063, 8.1533),
    (193, 8.5267, 16.6800),
    (375, 16.7278, 8.2011),
    (315, 11.6958, 19.8969),
    (403, 19.7218, 8.0260),
    (248, 11.0198, 19.0458),
    (501, 22.7595, 11.7397),
    (612, 8.4900, 20.2297),
)

TABLE4_DATASET2: tuple[PaperRow, ...] = (
    (0, 0.0, 0.0),
    (169, 9.2705, 9.2705),
    (266, 18.7485, 9.4780),
    (270, 6.4000, 15.8780),
    (248, 17.5027, 11.1027),
    (194, 7.9676, 19.0703),
    (205, 15.5098, 7.5422),
    (108, 8.5901, 16.1323),
    (73, 18.5680, 9.9779),
    (319, 7.7937, 17.7716),
    (274, 17.9803, 10.1866),
    (12, 6.4367, 16.6233),
    (216, 14.2391, 7.8024),
    (279, 9.2184, 17.0208),
    (302, 18.3551, 9.1368),
    (161, 9.0811, 18.2179),
    (326, 19.2275, 10.1464),
)

# Scenario spec → (table, the total length the paper reports for it in Section 5.2, metres).
PAPER_ROUTES: dict[str, tuple[str, tuple[PaperRow, ...], float]] = {
    "dataset1": ("Table 3", TABLE3_DATASET1, 116_861.0),
    "dataset2": ("Table 4", TABLE4_DATASET2, 140_131.0),
}
