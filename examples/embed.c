/* Embedding illum in a C application's Vulkan frame, the C counterpart of
 * examples/embed.rs: the application creates its own instance and a device with what
 * illum_requirements asks for (embed_host.h), builds a scene in code (a mesh and a texture from
 * its own arrays), and renders 10 progressive passes into its own storage image while orbiting
 * the camera (a new viewpoint and a turned mesh every second pass, which restarts the
 * accumulation), recording each pass into its own command buffer; it reads the image back and
 * writes it as a PFM, printing the time of each pass and of each update.
 *
 *   cc -std=c11 -I include -I examples examples/embed.c target/release/libillum.a \
 *      -lvulkan -lm -ldl -lpthread -lgcc_s -o embed
 *   ./embed [OUT.pfm [WIDTH HEIGHT [SPP [INTEGRATOR]]]]   (embed.pfm 160 120 16 direct)
 *
 * ILLUM_VALIDATION=1 turns the validation layers on (with synchronization validation); any
 * message then fails the run. Exit 0 on success. */
#define _POSIX_C_SOURCE 200809L
#include "embed_host.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

#define TRY(call)                                                                     \
    do {                                                                              \
        if ((call) != ILLUM_STATUS_OK) {                                              \
            fprintf(stderr, "embed: %s: %s\n", #call, illum_last_error());           \
            return 1;                                                                 \
        }                                                                             \
    } while (0)

/* A pyramid of 4 sides (its own vertices per face, for flat normals and uvs), turned by `angle`
 * radians about the vertical and placed at (x, 0, z). */
static void pyramid_transform(double angle, double m[16]) {
    const double c = cos(angle), s = sin(angle);
    const double r[16] = {c, 0, s, -0.9, 0, 1, 0, 0, -s, 0, c, 0.3, 0, 0, 0, 1};
    memcpy(m, r, sizeof r);
}

static IllumScene *build_scene(uint32_t width, uint32_t height) {
    const double position[3] = {0, 1.3, 3.2}, look_at[3] = {0, 0.4, 0};
    IllumSceneBuilder *b = NULL;
    IllumScene *scene = NULL;
    if (illum_scene_builder_create(position, look_at, 40, width, height, &b) != ILLUM_STATUS_OK) return NULL;
    /* The pyramid: apex (0, 1, 0) over the square |x|, |z| <= 0.5; 4 faces of 3 vertices. */
    const float apex[3] = {0, 1, 0};
    const float base[4][3] = {{-0.5f, 0, 0.5f}, {0.5f, 0, 0.5f}, {0.5f, 0, -0.5f}, {-0.5f, 0, -0.5f}};
    float positions[12 * 3], uvs[12 * 2];
    uint32_t indices[12];
    for (int f = 0; f < 4; f++) {
        const float *v[3] = {base[f], base[(f + 1) % 4], apex};
        const float uv[3][2] = {{0, 0}, {1, 0}, {0.5f, 1}};
        for (int k = 0; k < 3; k++) {
            memcpy(&positions[3 * (3 * f + k)], v[k], 12);
            memcpy(&uvs[2 * (3 * f + k)], uv[k], 8);
            indices[3 * f + k] = (uint32_t)(3 * f + k);
        }
    }
    /* An 8x8 checker of two colours, RGB. */
    float checker[8 * 8 * 3];
    for (int i = 0; i < 64; i++) {
        const int on = ((i % 8) + (i / 8)) % 2;
        checker[3 * i] = on ? 0.9f : 0.2f;
        checker[3 * i + 1] = on ? 0.8f : 0.3f;
        checker[3 * i + 2] = on ? 0.3f : 0.6f;
    }
    double m[16];
    pyramid_transform(0, m);
    int ok = illum_scene_builder_material(b, "floor", "{\"diffuse\": [0.6, 0.6, 0.6],"
                 " \"specular\": [{\"model\": \"ggx\", \"roughness\": 0.2}]}") == ILLUM_STATUS_OK
        && illum_scene_builder_material(b, "ball", "{\"diffuse\": [0.7, 0.3, 0.2]}") == ILLUM_STATUS_OK
        && illum_scene_builder_material(b, "checker", "{\"diffuse\": [1, 1, 1], \"diffuse_texture\": \"checker\"}")
               == ILLUM_STATUS_OK
        && illum_scene_builder_texture(b, "checker", 8, 8, 3, checker, 0) == ILLUM_STATUS_OK
        && illum_scene_builder_shape(b, "floor", "{\"rect\": {\"center\": [0, 0, 0], \"normal\": [0, 1, 0],"
               " \"size\": [6, 6]}, \"material\": \"floor\"}") == ILLUM_STATUS_OK
        && illum_scene_builder_shape(b, "ball", "{\"sphere\": {\"center\": [0.6, 0.5, 0], \"radius\": 0.5},"
               " \"material\": \"ball\"}") == ILLUM_STATUS_OK
        && illum_scene_builder_mesh(b, "pyramid", "checker", positions, NULL, uvs, 12, indices, 12, m)
               == ILLUM_STATUS_OK
        && illum_scene_builder_light(b, "key", "{\"rect\": {\"center\": [1, 2, 1], \"normal\": [-0.4, -1, -0.4],"
               " \"size\": [0.8, 0.8]}, \"intensity\": 6}") == ILLUM_STATUS_OK
        && illum_scene_builder_light(b, "sky", "{\"dome\": {}, \"color\": [0.2, 0.3, 0.4]}") == ILLUM_STATUS_OK
        && illum_scene_builder_build(b, &scene) == ILLUM_STATUS_OK;
    illum_scene_builder_destroy(b);
    return ok ? scene : NULL;
}

/* Portable float map: RGB, bottom row first, little-endian (negative scale). */
static int write_pfm(const char *path, const float *rgba, uint32_t w, uint32_t h) {
    FILE *f = fopen(path, "wb");
    if (!f) return 1;
    fprintf(f, "PF\n%u %u\n-1.0\n", w, h);
    for (uint32_t y = h; y-- > 0;)
        for (uint32_t x = 0; x < w; x++) fwrite(&rgba[4 * ((size_t)y * w + x)], 4, 3, f);
    return fclose(f) != 0;
}

int main(int argc, char **argv) {
    const char *out = argc > 1 ? argv[1] : "embed.pfm";
    const uint32_t w = argc > 3 ? (uint32_t)atoi(argv[2]) : 160, h = argc > 3 ? (uint32_t)atoi(argv[3]) : 120;
    const uint32_t spp = argc > 4 ? (uint32_t)atoi(argv[4]) : 16;
    const char *integrator = argc > 5 ? argv[5] : "direct";
    const char *v = getenv("ILLUM_VALIDATION");
    const int validation = v && strcmp(v, "1") == 0;
    if (w == 0 || h == 0 || spp < 2) {
        fprintf(stderr, "embed: WIDTH and HEIGHT must be positive, SPP at least 2\n");
        return 2;
    }
    Host host;
    if (host_create(&host, validation)) return 1;
    IllumExternalDevice ext = host_external(&host);
    IllumContext *ctx = NULL;
    TRY(illum_context_from_external(&ext, &ctx));

    IllumScene *scene = build_scene(w, h);
    if (!scene) {
        fprintf(stderr, "embed: building the scene: %s\n", illum_last_error());
        return 1;
    }
    double t = now_ms();
    IllumPrepared *prepared = NULL;
    TRY(illum_prepare(ctx, scene, &prepared));
    printf("prepare: %.1f ms\n", now_ms() - t);

    HostImage image;
    if (host_image_create(&host, &image, w, h)) return 1;
    IllumTarget target = host_image_target(&image);
    IllumSession *session = NULL;
    t = now_ms();
    TRY(illum_session_create(ctx, prepared, scene, integrator, 1, &target, &session));
    printf("session (%s): %.1f ms\n", integrator, now_ms() - t);
    /* Each viewpoint: a pass of spp/4 samples, then one of the rest. */
    const uint32_t first = spp / 4 > 0 ? spp / 4 : 1;
    for (int pass = 0; pass < 10; pass++) {
        if (pass % 2 == 0) {
            const double angle = (pass / 2) * 0.35;
            const double position[3] = {3.2 * sin(angle), 1.3, 3.2 * cos(angle)}, look_at[3] = {0, 0.4, 0};
            TRY(illum_scene_set_camera(scene, position, look_at));
            t = now_ms();
            TRY(illum_session_set_camera(session, scene));
            const double camera_ms = now_ms() - t;
            double m[16];
            pyramid_transform(angle, m);
            TRY(illum_scene_set_transform(scene, "pyramid", m));
            t = now_ms();
            TRY(illum_session_update_scene(session, scene));
            printf("update: camera %.3f ms, transform %.3f ms\n", camera_ms, now_ms() - t);
        }
        const uint32_t s0 = pass % 2 == 0 ? 0 : first, n = pass % 2 == 0 ? first : spp - first;
        t = now_ms();
        VkCommandBuffer cmd = host_begin(&host);
        TRY(illum_session_record_pass(session, cmd, s0, n));
        const double record_ms = now_ms() - t;
        if (host_end_and_wait(&host, &image, 1)) return 1;
        printf("pass %d: samples [%u, %u) in %.1f ms (recording %.3f ms; record, submit, wait, copy)\n", pass, s0,
               s0 + n, now_ms() - t, record_ms);
    }
    illum_session_destroy(session);
    /* The blocking render of the same samples, for comparison with the passes. */
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb), *rgba = malloc((size_t)w * h * 4 * sizeof *rgba);
    if (!rgb || !rgba) return 1;
    t = now_ms();
    TRY(illum_render(ctx, prepared, scene, spp, 1, rgb, (size_t)w * h * 3));
    printf("illum_render (blocking) of %u samples: %.1f ms\n", spp, now_ms() - t);
    if (host_image_read(&host, &image, rgba)) return 1;
    int finite = 1;
    for (size_t i = 0; i < (size_t)w * h * 4; i++) finite &= isfinite(rgba[i]) && rgba[i] >= 0;
    if (!finite) {
        fprintf(stderr, "embed: the image has negative or non-finite values\n");
        return 1;
    }
    if (write_pfm(out, rgba, w, h)) {
        fprintf(stderr, "embed: cannot write %s\n", out);
        return 1;
    }
    printf("wrote %s\n", out);
    free(rgb);
    free(rgba);
    illum_prepared_destroy(prepared);
    illum_scene_destroy(scene);
    illum_context_destroy(ctx);
    host_image_destroy(&host, &image);
    host_destroy(&host);
    if (host_validation_messages) {
        fprintf(stderr, "embed: %d validation messages\n", host_validation_messages);
        return 1;
    }
    return 0;
}
