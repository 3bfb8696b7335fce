/* The C API end to end, as a C or C++ engine uses it (run by tests/capi.rs): its own instance
 * (validation on, every message fails) and a device created with what illum_requirements asks
 * for (examples/embed_host.h), a scene from JSON and the same scene built in code (meshes and
 * textures from host memory), prepare, blocking render, an update, a pass recorded into the
 * host's own command buffer and image, which must equal the blocking render bit for bit, and a
 * panic inside illum that comes back as an error code. Exit 0 on success. */
#include "embed_host.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int failures = 0;

#define CHECK(cond, ...)                                                   \
    do {                                                                   \
        if (!(cond)) {                                                     \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                  \
            fprintf(stderr, "\n");                                         \
            failures++;                                                    \
        }                                                                  \
    } while (0)
#define OK(call) CHECK((call) == ILLUM_STATUS_OK, "%s", illum_last_error())

static const char *SCENE =
    "{\"camera\": {\"position\": [0, 1.2, 3], \"look_at\": [0, 0.3, 0], \"fov_y\": 40, \"resolution\": [13, 9]},"
    " \"materials\": {\"floor\": {\"diffuse\": [0.6, 0.6, 0.6]}, \"card\": {\"diffuse\": [0.2, 0.5, 0.7]}},"
    " \"shapes\": {\"floor\": {\"rect\": {\"center\": [0, 0, 0], \"normal\": [0, 1, 0], \"size\": [6, 6]}, \"material\": \"floor\"},"
    "   \"card\": {\"mesh\": {\"positions\": [[-0.4, 0, 0], [0.4, 0, 0], [0.4, 0.8, 0], [-0.4, 0.8, 0]], \"indices\": [0, 1, 2, 0, 2, 3]},"
    "              \"material\": \"card\", \"transform\": {\"translate\": [-0.2, 0, 0.2]}}},"
    " \"lights\": {\"key\": {\"rect\": {\"center\": [1, 2, 1], \"normal\": [-0.4, -1, -0.4], \"size\": [0.8, 0.8]}, \"intensity\": 6},"
    "   \"sky\": {\"dome\": {}, \"color\": [0.2, 0.3, 0.4]}}}";

enum { W = 13, H = 9, SPP = 4 };
static const uint64_t SEED = 11;

/* SCENE built in code; with `textured`, the card takes a 2x2 texture of `channels` floats a texel
 * through uvs (and has normals). NULL on error (illum_last_error says why). */
static IllumScene *build_scene(int textured, int channels) {
    const double position[3] = {0, 1.2, 3}, look_at[3] = {0, 0.3, 0};
    IllumSceneBuilder *b = NULL;
    IllumScene *scene = NULL;
    if (illum_scene_builder_create(position, look_at, 40, W, H, &b) != ILLUM_STATUS_OK) return NULL;
    const float positions[] = {-0.4f, 0, 0, 0.4f, 0, 0, 0.4f, 0.8f, 0, -0.4f, 0.8f, 0};
    const float normals[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const float uvs[] = {0, 0, 1, 0, 1, 1, 0, 1};
    const uint32_t indices[] = {0, 1, 2, 0, 2, 3};
    const double move[16] = {1, 0, 0, -0.2, 0, 1, 0, 0, 0, 0, 1, 0.2, 0, 0, 0, 1};
    const float texels[] = {1, 0.2f, 0.2f, 1, 0.2f, 1, 0.2f, 1, 0.2f, 0.2f, 1, 1, 1, 1, 1, 1};
    float rgb[12];
    for (int i = 0; i < 4; i++) memcpy(&rgb[3 * i], &texels[4 * i], 12);
    int ok = illum_scene_builder_material(b, "floor", "{\"diffuse\": [0.6, 0.6, 0.6]}") == ILLUM_STATUS_OK
        && illum_scene_builder_material(b, "card", textured
               ? "{\"diffuse\": [0.2, 0.5, 0.7], \"diffuse_texture\": \"checker\"}"
               : "{\"diffuse\": [0.2, 0.5, 0.7]}") == ILLUM_STATUS_OK
        && illum_scene_builder_shape(b, "floor", "{\"rect\": {\"center\": [0, 0, 0], \"normal\": [0, 1, 0],"
               " \"size\": [6, 6]}, \"material\": \"floor\"}") == ILLUM_STATUS_OK
        && illum_scene_builder_mesh(b, "card", "card", positions, textured ? normals : NULL,
               textured ? uvs : NULL, 4, indices, 6, move) == ILLUM_STATUS_OK
        && illum_scene_builder_light(b, "key", "{\"rect\": {\"center\": [1, 2, 1], \"normal\": [-0.4, -1, -0.4],"
               " \"size\": [0.8, 0.8]}, \"intensity\": 6}") == ILLUM_STATUS_OK
        && illum_scene_builder_light(b, "sky", "{\"dome\": {}, \"color\": [0.2, 0.3, 0.4]}") == ILLUM_STATUS_OK
        && (!textured || illum_scene_builder_texture(b, "checker", 2, 2, (uint32_t)channels,
               channels == 3 ? rgb : texels, 0) == ILLUM_STATUS_OK)
        && illum_scene_builder_build(b, &scene) == ILLUM_STATUS_OK;
    illum_scene_builder_destroy(b);
    return ok ? scene : NULL;
}

/* Bad input to the builder: a status and a message naming the object and field. */
static void check_builder_errors(void) {
    const double position[3] = {0, 0, 3}, look_at[3] = {0, 0, 0};
    IllumSceneBuilder *b = NULL;
    OK(illum_scene_builder_create(position, look_at, 40, 8, 8, &b));
    const float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t indices[] = {0, 1, 7};
    const float pixels[] = {1, 1, 1, 1};
    CHECK(illum_scene_builder_texture(b, "t", 1, 1, 2, pixels, 0) == ILLUM_STATUS_ERROR_INVALID, "2 channels");
    CHECK(strstr(illum_last_error(), "textures.t.pixels") != NULL, "message: %s", illum_last_error());
    CHECK(illum_scene_builder_mesh(b, "m", "m", NULL, NULL, NULL, 3, indices, 3, NULL) == ILLUM_STATUS_ERROR_NULL,
          "NULL positions");
    CHECK(strstr(illum_last_error(), "shapes.m.mesh.positions") != NULL, "message: %s", illum_last_error());
    CHECK(illum_scene_builder_material(b, "m", "{\"diffuse\": [0.5, 0.5]") == ILLUM_STATUS_ERROR_INVALID,
          "malformed JSON");
    CHECK(strstr(illum_last_error(), "materials.m") != NULL, "message: %s", illum_last_error());
    OK(illum_scene_builder_material(b, "m", "{\"diffuse\": [0.5, 0.5, 0.5]}"));
    OK(illum_scene_builder_mesh(b, "m", "m", positions, NULL, NULL, 3, indices, 3, NULL));
    IllumScene *scene = NULL;
    CHECK(illum_scene_builder_build(b, &scene) == ILLUM_STATUS_ERROR_INVALID, "index 7 of 3 vertices");
    CHECK(strstr(illum_last_error(), "shapes.m.mesh") != NULL, "message: %s", illum_last_error());
    CHECK(scene == NULL, "no scene on error");
    illum_scene_builder_destroy(b);
}

int main(void) {
    Host host;
    if (host_create(&host, 1)) return 2;
    const IllumRequirements req = host.req;
    CHECK(req.shader_int64 && req.buffer_device_address && req.scalar_block_layout, "base features");
    CHECK(req.extension_count == 0 && !req.ray_query, "the base set has no extension");
    IllumExternalDevice ext = host_external(&host);
    IllumContext *ctx = NULL;
    OK(illum_context_from_external(&ext, &ctx));

    /* Errors: a code and a message naming the field; NULL handles are refused. */
    IllumScene *bad = NULL;
    CHECK(illum_scene_from_json("{\"camera\": {\"position\": [0,0,3], \"look_at\": [0,0,0], \"fov_y\": 40},"
                                " \"materials\": {\"m\": {\"diffuse\": [2, 0, 0]}}, \"shapes\": {\"s\":"
                                " {\"sphere\": {\"center\": [0,0,0], \"radius\": 1}, \"material\": \"m\"}}}",
                                NULL, &bad) == ILLUM_STATUS_ERROR_INVALID, "a bad diffuse is invalid");
    CHECK(strstr(illum_last_error(), "materials.m.diffuse") != NULL, "message: %s", illum_last_error());
    CHECK(bad == NULL, "no scene on error");
    CHECK(illum_prepare(NULL, NULL, NULL) == ILLUM_STATUS_ERROR_NULL, "NULL context");

    /* A USD stage loads as a scene file does (the test runs in the repository root). */
    IllumScene *stage = NULL;
    OK(illum_scene_load("scenes/lookdev.usda", &stage));
    const char *warnings = NULL;
    uint32_t warning_count = 99;
    OK(illum_scene_warnings(stage, &warnings, &warning_count));
    CHECK(warning_count == 0 && strcmp(warnings, "") == 0, "lookdev: %u warnings: %s", warning_count, warnings);
    illum_scene_destroy(stage);
    /* A stage with what illum does not render: its warnings name the prims. */
    char path[64];
    snprintf(path, sizeof path, "/tmp/illum-capi-%d.usda", (int)getpid());
    FILE *f = fopen(path, "w");
    CHECK(f != NULL, "write %s", path);
    fputs("#usda 1.0\ndef Camera \"Cam\" {}\ndef DomeLight \"Sky\" {}\n"
          "def Points \"Dust\" {}\ndef BasisCurves \"Hair\" {}\n", f);
    fclose(f);
    OK(illum_scene_load(path, &stage));
    OK(illum_scene_warnings(stage, &warnings, &warning_count));
    CHECK(warning_count == 2 && strstr(warnings, "/Dust: Points") && strstr(warnings, "\n/Hair: BasisCurves"),
          "%u warnings: %s", warning_count, warnings);
    illum_scene_destroy(stage);
    remove(path);
    CHECK(illum_scene_load("scenes/nowhere.usda", &bad) != ILLUM_STATUS_OK, "a missing stage");
    CHECK(strstr(illum_last_error(), "nowhere.usda") != NULL, "message: %s", illum_last_error());

    IllumScene *scene = NULL;
    IllumPrepared *prepared = NULL;
    OK(illum_scene_from_json(SCENE, NULL, &scene));
    OK(illum_prepare(ctx, scene, &prepared));
    static float first[W * H * 3], edited[W * H * 3], reference[W * H * 3];
    CHECK(illum_render(ctx, prepared, scene, SPP, SEED, first, 10) == ILLUM_STATUS_ERROR_INVALID, "small buffer");
    OK(illum_render(ctx, prepared, scene, SPP, SEED, first, W * H * 3));
    double sum = 0;
    for (int i = 0; i < W * H * 3; i++) { CHECK(isfinite(first[i]), "pixel %d", i); sum += first[i]; }
    CHECK(sum > 0, "an image with light in it");

    /* An edit and a moved instance, then the same render: another image. */
    OK(illum_scene_set_diffuse(scene, "card", 0.9f, 0.1f, 0.1f));
    const double m[16] = {1, 0, 0, 0.3, 0, 1, 0, 0, 0, 0, 1, 0.4, 0, 0, 0, 1};
    OK(illum_scene_set_transform(scene, "card", m));
    OK(illum_prepared_update(prepared, scene));
    OK(illum_render(ctx, prepared, scene, SPP, SEED, edited, W * H * 3));
    CHECK(memcmp(first, edited, sizeof first) != 0, "the edit shows");
    CHECK(illum_scene_set_diffuse(scene, "card", 2.0f, 0, 0) == ILLUM_STATUS_ERROR_INVALID, "diffuse 2");
    CHECK(strstr(illum_last_error(), "materials.card.diffuse") != NULL, "message: %s", illum_last_error());
    OK(illum_render(ctx, prepared, scene, SPP, SEED, reference, W * H * 3));

    /* The same scene built in code gives the same image, bit for bit. */
    static float built[W * H * 3];
    IllumScene *built_scene = build_scene(0, 0);
    CHECK(built_scene != NULL, "the built scene: %s", illum_last_error());
    if (built_scene) {
        IllumPrepared *p = NULL;
        OK(illum_prepare(ctx, built_scene, &p));
        OK(illum_render(ctx, p, built_scene, SPP, SEED, built, W * H * 3));
        CHECK(memcmp(first, built, sizeof first) == 0, "the built scene renders as the JSON scene");
        illum_prepared_destroy(p);
        illum_scene_destroy(built_scene);
    }
    /* A texture from host pixels: RGB and RGBA (alpha 1) give the same image, and it shows. */
    static float rgb_texture[W * H * 3], rgba_texture[W * H * 3];
    for (int channels = 3; channels <= 4; channels++) {
        IllumScene *t = build_scene(1, channels);
        CHECK(t != NULL, "the textured scene (%d channels): %s", channels, illum_last_error());
        if (!t) continue;
        IllumPrepared *p = NULL;
        OK(illum_prepare(ctx, t, &p));
        OK(illum_render(ctx, p, t, SPP, SEED, channels == 3 ? rgb_texture : rgba_texture, W * H * 3));
        illum_prepared_destroy(p);
        illum_scene_destroy(t);
    }
    CHECK(memcmp(rgb_texture, rgba_texture, sizeof first) == 0, "RGB and RGBA textures agree");
    CHECK(memcmp(rgb_texture, first, sizeof first) != 0, "the texture shows");
    check_builder_errors();

    /* A panic inside illum: an error code and its message, and illum goes on working. */
    CHECK(illum_debug_panic("deliberate") == ILLUM_STATUS_ERROR_PANIC, "the panic's status");
    CHECK(strstr(illum_last_error(), "panic") && strstr(illum_last_error(), "deliberate"),
          "message: %s", illum_last_error());
    static float after_panic[W * H * 3];
    OK(illum_render(ctx, prepared, scene, SPP, SEED, after_panic, W * H * 3));
    CHECK(memcmp(after_panic, reference, sizeof first) == 0, "the same render after the panic");

    /* One pass of SPP samples into the host's image, copied out in the same command buffer. */
    HostImage image;
    CHECK(host_image_create(&host, &image, W, H) == 0, "the host's image");
    IllumTarget target = host_image_target(&image);
    IllumSession *session = NULL;
    CHECK(illum_session_create(ctx, prepared, scene, "nope", SEED, &target, &session) == ILLUM_STATUS_ERROR_INVALID,
          "an unknown integrator");
    CHECK(strstr(illum_last_error(), "\"nope\"") != NULL, "message: %s", illum_last_error());
    OK(illum_session_create(ctx, prepared, scene, NULL, SEED, &target, &session));
    CHECK(illum_session_add_aov_target(session, "Direct", &target) == ILLUM_STATUS_ERROR_INVALID,
          "direct has no AOV planes");
    CHECK(strstr(illum_last_error(), "writes none") != NULL, "message: %s", illum_last_error());
    OK(illum_session_record_pass(session, host_begin(&host), 0, SPP));
    CHECK(host_end_and_wait(&host, &image, 1) == 0, "the host's frame");
    static float texels[W * H * 4];
    CHECK(host_image_read(&host, &image, texels) == 0, "read back");
    int differing = 0;
    for (int i = 0; i < W * H; i++) {
        if (memcmp(&texels[4 * i], &reference[3 * i], 12) != 0 || texels[4 * i + 3] != 1.0f) differing++;
    }
    CHECK(differing == 0, "%d pixels of the recorded pass differ from the blocking render", differing);
    illum_session_destroy(session);

    illum_prepared_destroy(prepared);
    illum_scene_destroy(scene);
    illum_context_destroy(ctx);
    /* The device is still the host's. */
    host_image_destroy(&host, &image);
    host_destroy(&host);
    CHECK(host_validation_messages == 0, "%d validation messages", host_validation_messages);
    if (failures) { fprintf(stderr, "%d check(s) failed\n", failures); return 1; }
    printf("capi: ok\n");
    return 0;
}
