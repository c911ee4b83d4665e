# relMSE against render time, log-log, from `testbed render --report FILE.csv`.
#   gnuplot -e "in='report.csv'; out='report.png'" tools/plot-report.gp
# Several reports: in='a.csv b.csv' (one curve each, titled by file name).
# out ending in .svg writes SVG, anything else PNG.
if (!exists("in")) in = 'report.csv'
if (!exists("out")) out = 'report.png'
if (out[strlen(out)-3:] eq '.svg') {
    set terminal svg size 800,560 dynamic
} else {
    set terminal pngcairo size 800,560
}
set output out
set datafile separator ','
set key noenhanced
set logscale xy
set grid xtics ytics mxtics mytics
set xlabel 'seconds'
set ylabel 'relMSE against the reference'
set title 'testbed render: error against time'
plot for [f in in] f using 1:3 skip 1 with linespoints title f
