#!/usr/bin/env python3
"""One line per plan search of a `floorpose eval` debug log: the best place, the true one.

    echo 'tracking { global_search: true }' > search.conf
    build/tools/floorpose --log-level debug eval --plan P --recording R --config search.conf \
        > eval.log 2>&1
    tools/search-places.py eval.log

The debug log prints every place a search ranked, with its fit, inlier share, crossings,
rank and distance from the ground truth, then the search's decision. This prints, per
search: the simulated time, the best place (lowest rank, then lowest error) and how far it
is from the truth, the true place (the first within 1 m, or 'absent' when the search did
not return it) and the decision. A late placement is then either a ranking problem (the
true place returned but not first, or not of rank 0) or a missing place.
"""
import re
import sys

PLACE = re.compile(r"at ([\d.]+) s, truth: place scoring [\d.]+ \(fit ([\d.]+), (\d+)% inliers, "
                   r"(\d+) crossings.*?rank (\d)\) is ([\d.]+) m off")


def main(path):
    places = []
    with open(path, encoding="utf-8", errors="replace") as log:
        for line in log:
            m = PLACE.search(line)
            if m:
                t, fit, inl, cross, rank, off = m.groups()
                places.append((float(t), float(fit), int(inl), int(cross), int(rank), float(off)))
                continue
            if "global search:" not in line or not places:
                continue
            best = min(places, key=lambda p: (p[4], p[1]))
            true = next((p for p in places if p[5] < 1.0), None)
            text = "%7.1f s  best: fit %.4f, %3d%% inliers, %2d crossings, rank %d, %6.2f m off  " % (
                best[0], best[1], best[2], best[3], best[4], best[5])
            text += ("true: fit %.4f, %3d%%, %2d crossings, rank %d" % true[1:5]) if true else "true: absent"
            print(text + "  | " + line.split("global search: ", 1)[1].strip()[:120])
            places = []


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    try:
        main(sys.argv[1])
    except BrokenPipeError:
        pass
