// Written by tools/bench/mid2pov.py from tools/bench/pov/csg.mid; do not edit.
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 6 adc_bailout 1/255 ambient_light 0 }
background { rgb 0 }
// resolution 800 x 600
camera { perspective location <0, -13, 7> direction <0, 1.10149619, -0.493774156> right <1.33333333, -0, 0> up <0, 0.409055904, 0.912509325> }
light_source { <-7, -8, 10> rgb <477464.829, 477464.829, 477464.829> fade_distance 0.01 fade_power 2 }
light_source { <8, -5, 6> rgb <175070.437, 175070.437, 175070.437> fade_distance 0.01 fade_power 2 }
object { mesh { triangle { <-40, -30, 0>, <40, -30, 0>, <40, 60, 0> } triangle { <-40, -30, 0>, <40, 60, 0>, <-40, 60, 0> } } texture { pigment { rgb <0.6, 0.6, 0.55> } finish { ambient 0 diffuse 1 } } }  // ground
difference {  // csg 0 0
  intersection {  // 
    object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.6, -5.2, -1.5, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.81, 0, 0, 0, 0.81, 0, 0, 0, 0.81, -5.2, -1.5, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  union {  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.33, 0, 0, 0, 0.33, 0, 0, 0, 0.9, -5.2, -1.5, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.33, 0, 0, 0, 0, 0.33, 0, -0.9, 0, -5.2, -1.5, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0, 0, -0.33, 0, 0.33, 0, 0.9, 0, 0, -5.2, -1.5, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
}
intersection {  // csg 0 1
  object { sphere { <0, 0, 0>, 1 } matrix <0.717993786, 0.30477028, 0, -0.30477028, 0.717993786, 0, 0, 0, 0.78, -2.26861825, -1.35933679, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.717993786, 0.30477028, 0, -0.30477028, 0.717993786, 0, 0, 0, 0.78, -2.93138175, -1.64066321, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 0 2
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.416795022, 0.43160388, 0, -0.43160388, 0.416795022, 0, 0, 0, 0.6, 0, -1.5, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.541833529, 0.561085044, 0, -0.561085044, 0.541833529, 0, 0, 0, 0.78, 0, -1.5, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 0 3
  object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.21502077, 0.560148256, 0, -0.560148256, 0.21502077, 0, 0, 0, 0.6, 2.6, -1.5, 0.6> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.322531155, 0.840222384, 0, -0.140037064, 0.0537551924, 0, 0, 0, 0.36, 2.6, -1.5, 0.96> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.107510385, 0.280074128, 0, -0.280074128, 0.107510385, 0, 0, 0, 0.3, 2.6, -1.5, 1.2> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
intersection {  // csg 0 4
  union {  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.419744147, 0.0146577886, 0, -0.0146577886, 0.419744147, 0, 0, 0, 0.42, 5.4398538, -1.49162412, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.419744147, 0.0146577886, 0, -0.0146577886, 0.419744147, 0, 0, 0, 0.42, 4.9601462, -1.50837588, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.359780698, 0.0125638188, 0, -0.0125638188, 0.359780698, 0, 0, 0, 0.6, 5.2, -1.5, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.599634496, 0.020939698, 0, -0.020939698, 0.599634496, 0, 0, 0, 0.48, 5.2, -1.5, 0.48> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 1 0
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.479181306, 0.361089014, 0, -0.361089014, 0.479181306, 0, 0, 0, 0.6, -5.2, 0.9, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.622935698, 0.469415718, 0, -0.469415718, 0.622935698, 0, 0, 0, 0.78, -5.2, 0.9, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 1 1
  object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.3, 0.519615242, 0, -0.519615242, 0.3, 0, 0, 0, 0.6, -2.6, 0.9, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.45, 0.779422863, 0, -0.129903811, 0.075, 0, 0, 0, 0.36, -2.6, 0.9, 0.96> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.15, 0.259807621, 0, -0.259807621, 0.15, 0, 0, 0, 0.3, -2.6, 0.9, 1.2> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
intersection {  // csg 1 2
  union {  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.0511851242, 0.416869384, 0, -0.416869384, 0.0511851242, 0, 0, 0, 0.42, 0.0292486424, 1.13821108, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.0511851242, 0.416869384, 0, -0.416869384, 0.0511851242, 0, 0, 0, 0.42, -0.0292486424, 0.661788924, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.0438729636, 0.357316615, 0, -0.357316615, 0.0438729636, 0, 0, 0, 0.6, 0, 0.9, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.073121606, 0.595527691, 0, -0.595527691, 0.073121606, 0, 0, 0, 0.48, 0, 0.9, 0.48> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 1 3
  intersection {  // 
    object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.576757018, 0.165382413, 0, -0.165382413, 0.576757018, 0, 0, 0, 0.6, 2.6, 0.9, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.778621974, 0.223266258, 0, -0.223266258, 0.778621974, 0, 0, 0, 0.81, 2.6, 0.9, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  union {  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.31721636, 0.0909603274, 0, -0.0909603274, 0.31721636, 0, 0, 0, 0.9, 2.6, 0.9, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.31721636, 0.0909603274, 0, 0, 0, 0.33, 0.24807362, -0.865135526, 0, 2.6, 0.9, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0, 0, -0.33, -0.0909603274, 0.31721636, 0, 0.865135526, 0.24807362, 0, 2.6, 0.9, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
}
intersection {  // csg 1 4
  object { sphere { <0, 0, 0>, 1 } matrix <0.60617385, 0.490869905, 0, -0.490869905, 0.60617385, 0, 0, 0, 0.78, 5.47977255, 1.12655534, 0.6> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.60617385, 0.490869905, 0, -0.490869905, 0.60617385, 0, 0, 0, 0.78, 4.92022745, 0.673444659, 0.6> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
intersection {  // csg 2 0
  union {  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.115767689, 0.403729912, 0, -0.403729912, 0.115767689, 0, 0, 0, 0.42, -5.13384703, 3.53070281, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.115767689, 0.403729912, 0, -0.403729912, 0.115767689, 0, 0, 0, 0.42, -5.26615297, 3.06929719, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.0992294481, 0.346054211, 0, -0.346054211, 0.0992294481, 0, 0, 0, 0.6, -5.2, 3.3, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.165382413, 0.576757018, 0, -0.576757018, 0.165382413, 0, 0, 0, 0.48, -5.2, 3.3, 0.48> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 2 1
  intersection {  // 
    object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.595527691, 0.073121606, 0, -0.073121606, 0.595527691, 0, 0, 0, 0.6, -2.6, 3.3, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.803962383, 0.0987141682, 0, -0.0987141682, 0.803962383, 0, 0, 0, 0.81, -2.6, 3.3, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  union {  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.32754023, 0.0402168833, 0, -0.0402168833, 0.32754023, 0, 0, 0, 0.9, -2.6, 3.3, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.32754023, 0.0402168833, 0, 0, 0, 0.33, 0.109682409, -0.893291536, 0, -2.6, 3.3, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0, 0, -0.33, -0.0402168833, 0.32754023, 0, 0.893291536, 0.109682409, 0, -2.6, 3.3, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
}
intersection {  // csg 2 2
  object { sphere { <0, 0, 0>, 1 } matrix <0.675499815, 0.39, 0, -0.39, 0.675499815, 0, 0, 0, 0.78, 0.311769145, 3.48, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.675499815, 0.39, 0, -0.39, 0.675499815, 0, 0, 0, 0.78, -0.311769145, 3.12, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 2 3
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.361089014, 0.479181306, 0, -0.479181306, 0.361089014, 0, 0, 0, 0.6, 2.6, 3.3, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.469415718, 0.622935698, 0, -0.622935698, 0.469415718, 0, 0, 0, 0.78, 2.6, 3.3, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 2 4
  object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.145153137, 0.582177436, 0, -0.582177436, 0.145153137, 0, 0, 0, 0.6, 5.2, 3.3, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.217729706, 0.873266154, 0, -0.145544359, 0.0362882843, 0, 0, 0, 0.36, 5.2, 3.3, 0.96> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.0725765687, 0.291088718, 0, -0.291088718, 0.0725765687, 0, 0, 0, 0.3, 5.2, 3.3, 1.2> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
intersection {  // csg 3 0
  object { sphere { <0, 0, 0>, 1 } matrix <0.728192733, 0.279527001, 0, -0.279527001, 0.728192733, 0, 0, 0, 0.78, -4.86391105, 5.82901246, 0.6> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.728192733, 0.279527001, 0, -0.279527001, 0.728192733, 0, 0, 0, 0.78, -5.53608895, 5.57098754, 0.6> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 3 1
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.43160388, 0.416795022, 0, -0.416795022, 0.43160388, 0, 0, 0, 0.6, -2.6, 5.7, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.561085044, 0.541833529, 0, -0.541833529, 0.561085044, 0, 0, 0, 0.78, -2.6, 5.7, 0.6> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 3 2
  object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.234438677, 0.552302912, 0, -0.552302912, 0.234438677, 0, 0, 0, 0.6, 0, 5.7, 0.6> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.351658016, 0.828454368, 0, -0.138075728, 0.0586096693, 0, 0, 0, 0.36, 0, 5.7, 0.96> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.117219339, 0.276151456, 0, -0.276151456, 0.117219339, 0, 0, 0, 0.3, 0, 5.7, 1.2> texture { pigment { rgb <0.4, 0.15, 0.6> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
intersection {  // csg 3 3
  union {  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.42, 0, 0, 0, 0.42, 0, 0, 0, 0.42, 2.84, 5.7, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.42, 0, 0, 0, 0.42, 0, 0, 0, 0.42, 2.36, 5.7, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.36, 0, 0, 0, 0.36, 0, 0, 0, 0.6, 2.6, 5.7, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.48, 2.6, 5.7, 0.48> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
difference {  // csg 3 4
  intersection {  // 
    object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.552302912, 0.234438677, 0, -0.234438677, 0.552302912, 0, 0, 0, 0.6, 5.2, 5.7, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { sphere { <0, 0, 0>, 1 } matrix <0.745608931, 0.316492214, 0, -0.316492214, 0.745608931, 0, 0, 0, 0.81, 5.2, 5.7, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
  union {  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.303766602, 0.128941272, 0, -0.128941272, 0.303766602, 0, 0, 0, 0.9, 5.2, 5.7, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.303766602, 0.128941272, 0, 0, 0, 0.33, 0.351658016, -0.828454368, 0, 5.2, 5.7, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
    object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0, 0, -0.33, -0.128941272, 0.303766602, 0, 0.828454368, 0.351658016, 0, 5.2, 5.7, 0.6> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  }
}
