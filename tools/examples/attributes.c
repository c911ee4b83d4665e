/* Attributes for renderers: a MID file may carry attributes this library
 * does not know (`my_renderer_weight = 2.5` in an object), and the loaded
 * scene keeps them so that a renderer can read its own extensions
 * (docs/rendering.md, "Attributes for renderers"). This prints one such
 * attribute of every top-level object, or the default the renderer would
 * use where an object has none.
 *
 *     attributes SCENE.mid [NAME]      (NAME: my_renderer_weight)
 */
#include <stdio.h>

#include "host/render/scene.h"

/* A value as MID writes the simple kinds; the others by their kind. */
static void print_value(const tb_mid_value *v)
{
    switch (v->type) {
    case TB_MID_NUMBER: printf("%g", v->number); break;
    case TB_MID_STRING: printf("\"%s\"", v->text); break;
    case TB_MID_SYMBOL: printf("%s", v->text); break;
    case TB_MID_VECTOR:
        printf("[");
        for (int i = 0; i < v->count; i++)
            printf(i ? " %g" : "%g", v->numbers[i]);
        printf("]");
        break;
    case TB_MID_FILE: printf("file(\"%s\")", v->ref.text); break;
    case TB_MID_LIST: printf("(a list of %d values)", v->count); break;
    case TB_MID_CALL: printf("(a call of %s)", v->name); break;
    case TB_MID_BLOCK: printf("(a block of %d attributes)", v->count); break;
    }
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: attributes SCENE.mid [NAME]\n");
        return 2;
    }
    const char *name = argc > 2 ? argv[2] : "my_renderer_weight";

    /* No rays are traced: no acceleration structure is needed. */
    tb_scene_options opt = {.no_accel = true};
    tb_scene *s;
    if (tb_scene_load(argv[1], &opt, &s)) {
        fprintf(stderr, "attributes: %s\n", tb_last_error());
        return 1;
    }
    for (uint32_t i = 0; i < s->nobjects; i++) {
        const tb_object *o = s->objects[i];
        printf("%u %s%s%s: ", i, o->name ? "'" : "", o->name ? o->name : "(unnamed)", o->name ? "'" : "");
        /* The object's body, then its geometry block; NULL when neither has it. */
        const tb_mid_value *v = tb_scene_object_attr(s, i, name);
        if (v) {
            printf("%s = ", name);
            print_value(v);
            printf("\n");
        } else {
            /* What a renderer does with a missing attribute: its own default. */
            printf("%s not set (default %g)\n", name, tb_scene_attr_number(v, 1.0));
        }
    }
    tb_scene_free(s);
    return 0;
}
