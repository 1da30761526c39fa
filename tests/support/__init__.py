"""What the tests share, by purpose: paths of the repository and its data, scenario builders,
brute-force fronts, missions and flights, and the like. Tests import these from here, never
from another test file, so that a test file can move to any folder under tests/."""
