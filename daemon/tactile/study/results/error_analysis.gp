# Renders error_analysis.dat (written by tactile_error_analysis) as a clustered bar chart:
#   gnuplot -e "datadir='daemon/tactile/study/results'" daemon/tactile/study/results/error_analysis.gp
if (!exists("datadir")) datadir = "."
set terminal pngcairo size 1100,560 font "sans,10"
set bmargin 7
set output datadir."/error_analysis.png"
set title "Thimble rendering: force error |F_d - F_v| / |F_v| per virtual contact (bars clipped at 120 %)"
set ylabel "force error (%)"
set yrange [0:120]
set grid ytics
set style data histogram
set style histogram cluster gap 1
set style fill solid 0.85 border -1
set boxwidth 0.9
set xtics rotate by -30 scale 0 font ",9"
set key top left
plot datadir."/error_analysis.dat" using 3:xtic(2) title "contact optimiser" lc rgb "#1b9e77", \
     "" using 4 title "geometric plane fit" lc rgb "#7570b3", \
     "" using 5 title "force-normal displacement" lc rgb "#d95f02"
