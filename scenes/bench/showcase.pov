// Written by tools/bench/mid2pov.py from scenes/showcase.mid; do not edit.
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 6 ambient_light 0 }
background { rgb 0 }
// resolution 960 x 540
camera { perspective location <0, -11, 4.5> direction <0, 1.39943761, -0.387536568> right <1.77777778, -0, 0> up <0, 0.266879083, 0.963730022> }
light_source { <400, -600, 1000> rgb <0.636619772, 0.604788784, 0.541126807> parallel point_at <0, 0, 0> }
light_source { <-3, -4, 5> rgb <63661.9772, 63661.9772, 63661.9772> fade_distance 0.01 fade_power 2 }
light_source { <0, -1, 6> rgb <190985.932, 175070.437, 143239.449> spotlight point_at <-0.3, 1.2, 0.8> radius 19 falloff 25 tightness 0 fade_distance 0.01 fade_power 2 }
object { mesh { triangle { <-12, -8, 0>, <12, -8, 0>, <12, 14, 0> } triangle { <-12, -8, 0>, <12, 14, 0>, <-12, 14, 0> } } texture { pigment { rgb <0.5, 0.5, 0.45> } finish { ambient 0 diffuse 1 } } }  // ground
difference {  // dice cup
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.422861679, -0.153909064, 0, 0.153909064, 0.422861679, 0, 0, 0, 0.45, -4.6, -1.2, 0.45> texture { pigment { rgb <0.72, 0.58, 0.4> } finish { ambient 0 diffuse 1 } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.549720183, -0.200081784, 0, 0.200081784, 0.549720183, 0, 0, 0, 0.585, -4.6, -1.2, 0.45> texture { pigment { rgb <0.72, 0.58, 0.4> } finish { ambient 0 diffuse 1 } } }  // 
}
object { intersection { quadric { <1, 1, 1>, <0, 0, 0>, <0, 0, -0>, -1 } plane { <0, 0, 1>, 1 } plane { <0, 0, -1>, 1 } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.45, 0, 0, 0, 0.45, 0, 0, 0, 0.6, -3.2, -2, 0.6> texture { pigment { rgb <0.35, 0.25, 0.05> } finish { ambient 0 diffuse 1 phong 60.6 phong_size 200 reflection { rgb <0.6, 0.5, 0.2> } } } }  // egg
object { sphere { <0, 0, 0>, 1 } matrix <0.7, 0, 0, 0, 0.7, 0, 0, 0, 0.7, -1, -2, 0.7> texture { pigment { rgbt <1, 1, 1, 0.9> } finish { ambient 0 diffuse 0 phong 250.05 phong_size 10000 reflection { 0, 1 fresnel on } conserve_energy } } interior { ior 1.5 } }  // glass ball
difference {  // csg classic
  intersection {  // 
    object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.519615242, 0.3, 0, -0.3, 0.519615242, 0, 0, 0, 0.6, 1.3, -2, 0.6> texture { pigment { rgb <0.1, 0.2, 0.6> } finish { ambient 0 diffuse 1 phong 16.4 phong_size 80 reflection { rgb <0.4, 0.4, 0.4> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.701480577, 0.405, 0, -0.405, 0.701480577, 0, 0, 0, 0.81, 1.3, -2, 0.6> texture { pigment { rgb <0.1, 0.2, 0.6> } finish { ambient 0 diffuse 1 phong 16.4 phong_size 80 reflection { rgb <0.4, 0.4, 0.4> } } } }  // 
  }
  union {  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.285788383, 0.165, 0, -0.165, 0.285788383, 0, 0, 0, 0.9, 1.3, -2, 0.6> texture { pigment { rgb <0.7, 0.15, 0.1> } finish { ambient 0 diffuse 1 } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.285788383, 0.165, 0, 0, 0, 0.33, 0.45, -0.779422863, 0, 1.3, -2, 0.6> texture { pigment { rgb <0.7, 0.15, 0.1> } finish { ambient 0 diffuse 1 } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0, 0, -0.33, -0.165, 0.285788383, 0, 0.779422863, 0.45, 0, 1.3, -2, 0.6> texture { pigment { rgb <0.7, 0.15, 0.1> } finish { ambient 0 diffuse 1 } } }  // 
  }
}
object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.453153894, 0.211309131, 0, -0.211309131, 0.453153894, 0, 0, 0, 0.5, 3.3, -1.8, 0.5> texture { pigment { rgb <0.55, 0.35, 0.18> } finish { ambient 0 diffuse 1 } } }  // crate
object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 open } matrix <0, 0, -0.3, 0, 0.3, 0, 0.8, 0, 0, 2.2, -0.6, 0.3> texture { pigment { rgb <0.4, 0.12, 0.4> } finish { ambient 0 diffuse 1 phong 4 phong_size 30 reflection { rgb <0.25, 0.25, 0.25> } } } }  // pipe
object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.3, 0, 0, 0, 0.3, 0, 0, 0, 1, -4.4, 1, 1> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // column
light_source { <0, 0, 0> rgb <4297.18346, 3867.46512, 2864.78898> fade_distance 0.01 fade_power 2 area_light <0.6, 0, 0>, <0, 0.6, 0>, 2, 2 circular orient jitter looks_like { object { sphere { <0, 0, 0>, 1 } matrix <0.3, 0, 0, 0, 0.3, 0, 0, 0, 0.3, 0, 0, 0> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 emission <9.54929659, 8.59436693, 6.36619772> } } } } translate <-4.4, 1, 2.3> }  // lamp globe
object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.9, -2.5, 1, 0.9> texture { pigment { rgb <0.15, 0.5, 0.2> } finish { ambient 0 diffuse 1 phong 6.3 phong_size 40 reflection { rgb <0.3, 0.3, 0.3> } } } }  // cone
object { sphere { <0, 0, 0>, 1 } matrix <0.8, 0, 0, 0, 0.8, 0, 0, 0, 0.8, -0.3, 1.2, 0.8> texture { pigment { rgb <0, 0, 0> } finish { ambient 0 diffuse 1 phong 4500.9 phong_size 10000 reflection { rgb <0.9, 0.9, 0.9> } } } }  // mirror ball
object { torus { 1, 0.3 matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0> } matrix <0.7, 0, 0, 0, 0.7, 0, 0, 0, 0.7, 1.9, 0.8, 0.21> texture { pigment { rgb <0.35, 0.25, 0.05> } finish { ambient 0 diffuse 1 phong 60.6 phong_size 200 reflection { rgb <0.6, 0.5, 0.2> } } } }  // ring
object { intersection { plane { <0, 0, 1>, 1 } plane { <0, 0, -1>, 1 } plane { <0.866025404, 0.5, 0>, 0.866025404 } plane { <1.11022302e-16, 1, 0>, 0.866025404 } plane { <-0.866025404, 0.5, 0>, 0.866025404 } plane { <-0.866025404, -0.5, 0>, 0.866025404 } plane { <-2.22044605e-16, -1, 0>, 0.866025404 } plane { <0.866025404, -0.5, 0>, 0.866025404 } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.5, 0, 0, 0, 0.5, 0, 0, 0, 0.6, 4, 1, 0.6> texture { pigment { rgb <0.4, 0.12, 0.4> } finish { ambient 0 diffuse 1 phong 4 phong_size 30 reflection { rgb <0.25, 0.25, 0.25> } } } }  // hex prism
object { intersection { plane { <0, 0, -1>, 1 } plane { <0.894427191, 0, 0.447213595>, 0.447213595 } plane { <-0.894427191, 0, 0.447213595>, 0.447213595 } plane { <0, 0.894427191, 0.447213595>, 0.447213595 } plane { <0, -0.894427191, 0.447213595>, 0.447213595 } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.751754097, 0.273616115, 0, -0.273616115, 0.751754097, 0, 0, 0, 0.8, -3.6, 3.5, 0.8> texture { pigment { rgb <0.72, 0.58, 0.4> } finish { ambient 0 diffuse 1 } } }  // pyramid
object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0.45 open } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.5, -1.6, 3.5, 0.5> texture { pigment { rgb <0.7, 0.15, 0.1> } finish { ambient 0 diffuse 1 } } }  // pot
object { object { quadric { <1, 1, -0.5>, <0, 0, 0>, <0, 0, -0>, -0.5 } clipped_by { plane { <0, 0, 1>, 1 } plane { <0, 0, -1>, 1 } } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 1.2, 0.4, 3.6, 1.2> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // tower
object { intersection { poly { 2, <1, 0, 0, 0, 1, 0, 0, 0, 0.5, -0.5> } plane { <0, 0, 1>, 1 } plane { <0, 0, -1>, 1 } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.7, 0, 0, 0, 0.7, 0, 0, 0, 0.6, 2.4, 3.4, 0.6> texture { pigment { rgb <0.1, 0.2, 0.6> } finish { ambient 0 diffuse 1 phong 16.4 phong_size 80 reflection { rgb <0.4, 0.4, 0.4> } } } }  // dome
object { prism { linear_sweep linear_spline -1, 1, 11, <0, 1>, <-0.2645, 0.3641>, <-0.9511, 0.309>, <-0.428, -0.1391>, <-0.5878, -0.809>, <0, -0.45>, <0.5878, -0.809>, <0.428, -0.1391>, <0.9511, 0.309>, <0.2645, 0.3641>, <0, 1> matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0> } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.25, 4.4, 3.4, 0.25> texture { pigment { rgb <0.7, 0.15, 0.1> } finish { ambient 0 diffuse 1 } } }  // star
object { intersection { plane { <0, 0, -1>, 1 } plane { <0, 0, 1>, 1 } plane { <0.9701425, 0, 0.242535625>, 0.727606875 } plane { <-0.9701425, 0, 0.242535625>, 0.727606875 } plane { <0, 0.9701425, 0.242535625>, 0.727606875 } plane { <0, -0.9701425, 0.242535625>, 0.727606875 } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.8, 0, 0, 0, 0.8, 0, 0, 0, 0.4, -5.5, 6.5, 0.4> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // plinth
object { difference { box { <-1, -1, -1>, <1, 1, 1> } box { <-0.6, -2, -2>, <0.6, 2, 0.5> } } matrix <1.2, 0, 0, 0, 0.3, 0, 0, 0, 1.2, -3, 6.5, 1.2> texture { pigment { rgb <0.72, 0.58, 0.4> } finish { ambient 0 diffuse 1 } } }  // gate
union {  // snowman
  object { sphere { <0, 0, 0>, 1 } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.6, 0, 6.5, 0.6> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.45, 0, 0, 0, 0.45, 0, 0, 0, 0.45, 0, 6.5, 1.5> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.3, 0, 0, 0, 0.3, 0, 0, 0, 0.3, 0, 6.5, 2.15> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // 
}
object { difference { box { <-1, -1, -1>, <1, 1, 1> } union { box { <-0.5, -2, -2>, <0.5, 2, 0> } cylinder { <0, -2, 0>, <0, 2, 0>, 0.5 } } } matrix <1.2, 0, 0, 0, 0.3, 0, 0, 0, 1.2, 2.8, 6.5, 1.2> texture { pigment { rgb <0.72, 0.58, 0.4> } finish { ambient 0 diffuse 1 } } }  // arch
intersection {  // die
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.434666622, 0.11646857, 0, -0.11646857, 0.434666622, 0, 0, 0, 0.45, 5.3, 6.3, 0.45> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.608533271, 0.163055998, 0, -0.163055998, 0.608533271, 0, 0, 0, 0.63, 5.3, 6.3, 0.45> texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 phong 3.1 phong_size 60 reflection { rgb <0.1, 0.1, 0.1> } } } }  // 
}
