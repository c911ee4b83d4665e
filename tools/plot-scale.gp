# Time to the first pixel and peak memory against the object count, log-log,
# from `testbed bench scale --csv FILE` (docs/performance.md, "Scale").
#   gnuplot -e "in='grid.csv mesh.csv csg.csv'; out='scale.png'" tools/plot-scale.gp
# One curve per file (titled by its kind); out ending in .svg writes SVG, anything else PNG.
if (!exists("in")) in = 'scale.csv'
if (!exists("out")) out = 'scale.png'
if (out[strlen(out)-3:] eq '.svg') {
    set terminal svg size 1000,420 dynamic
} else {
    set terminal pngcairo size 1000,420
}
set output out
set datafile separator ','
set key noenhanced top left
set logscale xy
set grid xtics ytics mxtics mytics
set format x '10^{%L}'
set xlabel 'top-level objects N'
set multiplot layout 1,2 title 'testbed bench scale (2 threads)'
set ylabel 'seconds'
set title 'load + build + first pixel'
plot for [f in in] f using 2:7 skip 1 with linespoints title f
set ylabel 'MiB'
set title 'peak resident memory'
plot for [f in in] f using 2:8 skip 1 with linespoints title f
unset multiplot
