// Written by tools/bench/mid2pov.py from tools/bench/pov/glass.mid; do not edit.
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 6 adc_bailout 1/255 ambient_light 0 }
background { rgb 0 }
// resolution 800 x 600
camera { perspective location <0, -9, 3.2> direction <0, 1.33878418, -0.307920362> right <1.33333333, -0, 0> up <0, 0.224147693, 0.974555187> }
light_source { <-5, -6, 8> rgb <318309.886, 318309.886, 318309.886> fade_distance 0.01 fade_power 2 }
light_source { <4, 6, 6> rgb <143239.449, 143239.449, 143239.449> fade_distance 0.01 fade_power 2 }
object { mesh { triangle { <-40, -30, 0>, <40, -30, 0>, <40, 60, 0> } triangle { <-40, -30, 0>, <40, 60, 0>, <-40, 60, 0> } } texture { pigment { rgb <0.55, 0.55, 0.5> } finish { ambient 0 diffuse 1 } } }  // ground
object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.563815572, 0.205212086, 0, -0.205212086, 0.563815572, 0, 0, 0, 1.2, -2.4, 3.5, 1.2> texture { pigment { rgb <0.75, 0.12, 0.1> } finish { ambient 0 diffuse 1 } } }  // red block
object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.45, 0, 0, 0, 0.45, 0, 0, 0, 1.5, 0, 4, 1.5> texture { pigment { rgb <0.15, 0.6, 0.2> } finish { ambient 0 diffuse 1 } } }  // green column
object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.7, 0, 0, 0, 0.7, 0, 0, 0, 1.1, 2.6, 3.4, 1.1> texture { pigment { rgb <0.15, 0.2, 0.7> } finish { ambient 0 diffuse 1 } } }  // blue cone
object { sphere { <0, 0, 0>, 1 } matrix <0.9, 0, 0, 0, 0.9, 0, 0, 0, 0.9, 4.4, 1.2, 0.9> texture { pigment { rgb <0, 0, 0> } finish { ambient 0 diffuse 1 phong 4250.85 phong_size 10000 reflection { rgb <0.85, 0.85, 0.85> } } } }  // mirror ball
object { torus { 0.8, 0.3 matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0> } matrix <1, 0, 0, 0, 1, 0, 0, 0, 1, -4.2, 1.5, 0.3> texture { pigment { rgb <0.75, 0.65, 0.12> } finish { ambient 0 diffuse 1 } } }  // yellow ring
object { sphere { <0, 0, 0>, 1 } matrix <0.9, 0, 0, 0, 0.9, 0, 0, 0, 0.9, -1.4, 0, 0.9> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // glass ball
object { sphere { <0, 0, 0>, 1 } matrix <0.5, 0, 0, 0, 0.5, 0, 0, 0, 0.5, 0.9, -1.6, 0.5> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // small glass ball
object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.35, 0, 0, 0, 0.35, 0, 0, 0, 1.1, 1.4, 0.8, 1.1> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // glass rod
object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.787846202, -0.138918542, 0, 0.0260472267, 0.147721163, 0, 0, 0, 0.7, -3.4, -0.8, 0.7> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // glass slab
intersection {  // lens
  object { sphere { <0, 0, 0>, 1 } matrix <1.2, 0, 0, 0, 0, 1.2, 0, -1.2, 0, 3, 0.15, 0.9> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <1.2, 0, 0, 0, 0, 1.2, 0, -1.2, 0, 3, -1.75, 0.9> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // 
}
