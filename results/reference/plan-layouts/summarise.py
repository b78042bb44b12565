#!/usr/bin/env python3
"""Summarises the layout accuracy of every annotated plan (the accuracy.json files written by
`floorcast layout --map PLAN.xml --truth PLAN.xml --out DIR/NAME`) as a CSV on stdout and the
means per kind (school, office) on stderr. Usage: summarise.py DIR"""
import csv, glob, json, os, statistics, sys

out = csv.writer(sys.stdout)
out.writerow(["plan", "kind", "rooms_true", "rooms_found", "matched_room_iou", "pixel_accuracy"])
rows = []
for acc in sorted(glob.glob(os.path.join(sys.argv[1], "*", "accuracy.json"))):
    j = json.load(open(acc))
    text = open(j["truth"], encoding="utf-8").read()
    kind = "school" if "<main_type>SCHOOL" in text else "office"
    name = os.path.basename(os.path.dirname(acc))
    rows.append((name, kind, j["rooms_true"], j["rooms_found"], j["matched_room_iou"], j["pixel_accuracy"]))
    out.writerow([name, kind, j["rooms_true"], j["rooms_found"], f"{j['matched_room_iou']:.3f}", f"{j['pixel_accuracy']:.3f}"])
for kind in ["school", "office"]:
    r = [x for x in rows if x[1] == kind]
    if r:
        iou = [x[4] for x in r]
        print(f"{kind}: {len(r)} plans, matched room IoU mean {statistics.mean(iou):.3f} median "
              f"{statistics.median(iou):.3f} min {min(iou):.3f}, pixel accuracy mean "
              f"{statistics.mean(x[5] for x in r):.3f}, rooms found per true room mean "
              f"{statistics.mean(x[3] / x[2] for x in r):.2f}", file=sys.stderr)
