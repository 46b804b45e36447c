#!/bin/sh
# report.sh CSV: prints the rows the benchmarks appended to CSV (see
# bench_report.h) as one table, then the targets with their status. Exit status
# 0 even when a target is missed: the table says so.
csv=${1:?usage: report.sh RESULTS.csv}
[ -s "$csv" ] || { echo "report.sh: no results in $csv" >&2; exit 1; }
echo
echo "== summary ($csv)"
awk -F, '
NR == 1 { next }
{ rows[NR] = $0 }
END {
    printf "%-9s %-44s %-26s %12s %-10s %-12s %s\n", "bench", "configuration", "metric",
           "value", "unit", "target", "status"
    for (i = 2; i <= NR; ++i) {
        split(rows[i], f, ",")
        printf "%-9s %-44s %-26s %12s %-10s %-12s %s\n", f[1], f[2], f[3], f[4], f[5], f[6], f[7]
    }
}' "$csv"
met=$(awk -F, 'NR > 1 && $7 == "met"' "$csv" | wc -l)
missed=$(awk -F, 'NR > 1 && $7 == "MISSED"' "$csv" | wc -l)
echo
echo "targets: $met met, $missed missed"
if [ "$missed" -gt 0 ]; then
    awk -F, 'NR > 1 && $7 == "MISSED" { printf "  MISSED  %s / %s / %s: %s %s (target %s)\n", $1, $2, $3, $4, $5, $6 }' "$csv"
fi
exit 0
