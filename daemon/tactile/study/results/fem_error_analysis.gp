# Renders fem_error_analysis.dat (written by tactile_fem_error_analysis) as a clustered bar chart:
#   gnuplot -e "datadir='daemon/tactile/study/results'" daemon/tactile/study/results/fem_error_analysis.gp
if (!exists("datadir")) datadir = "."
set terminal pngcairo size 1100,560 font "sans,10"
set bmargin 8
set output datadir."/fem_error_analysis.png"
set title "Thimble rendering against the FEM fingertip: force error |F_d - F_v| / |F_v| per virtual contact (bars clipped at 120 %)"
set ylabel "force error (%)"
set yrange [0:120]
set grid ytics
set style data histogram
set style histogram cluster gap 1
set style fill solid 0.85 border -1
set boxwidth 0.9
set xtics rotate by -30 scale 0 font ",9"
set key top left
plot datadir."/fem_error_analysis.dat" using 3:xtic(2) title "contact optimiser, cold" lc rgb "#1b9e77", \
     "" using 4 title "contact optimiser, warm" lc rgb "#66a61e", \
     "" using 5 title "geometric plane fit" lc rgb "#7570b3", \
     "" using 6 title "force-normal displacement" lc rgb "#d95f02"
