/* The C API end to end, as a C or C++ engine uses it (run by tests/capi.rs): its own instance
 * (validation on, every message fails), a device created with what illum_requirements asks for,
 * a scene from JSON, prepare, blocking render, an update, and a pass recorded into the host's own
 * command buffer and image, which must equal the blocking render bit for bit. Exit 0 on success. */
#include "illum.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;
static int validation_messages = 0;

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
#define VK(call) CHECK((call) == VK_SUCCESS, "Vulkan call failed")

static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(
    VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT types,
    const VkDebugUtilsMessengerCallbackDataEXT *data, void *user) {
    (void)severity; (void)types; (void)user;
    fprintf(stderr, "[validation] %s\n", data->pMessage);
    validation_messages++;
    return VK_FALSE;
}

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

static uint32_t memory_type(VkPhysicalDevice pd, uint32_t bits, VkMemoryPropertyFlags want) {
    VkPhysicalDeviceMemoryProperties p;
    vkGetPhysicalDeviceMemoryProperties(pd, &p);
    for (uint32_t i = 0; i < p.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (p.memoryTypes[i].propertyFlags & want) == want) return i;
    return 0;
}

int main(void) {
    /* The host's instance, with validation and synchronization validation. */
    const char *layers[] = {"VK_LAYER_KHRONOS_validation"};
    const char *exts[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
    VkValidationFeaturesEXT features = {VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, NULL, 1, &sync, 0, NULL};
    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO, NULL, "capi test", 1, NULL, 0, VK_API_VERSION_1_2};
    VkInstanceCreateInfo ici = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, &features, 0, &app, 1, layers, 1, exts};
    VkInstance instance;
    if (vkCreateInstance(&ici, NULL, &instance) != VK_SUCCESS) { fprintf(stderr, "no instance\n"); return 2; }
    PFN_vkCreateDebugUtilsMessengerEXT create_messenger =
        (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT");
    PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger =
        (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT");
    VkDebugUtilsMessengerCreateInfoEXT mci = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT, NULL, 0,
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
        VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
            VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
        on_message, NULL};
    VkDebugUtilsMessengerEXT messenger;
    VK(create_messenger(instance, &mci, NULL, &messenger));
    uint32_t n = 1;
    VkPhysicalDevice pd;
    vkEnumeratePhysicalDevices(instance, &n, &pd);

    /* What illum needs, asked; a device created with exactly that. */
    IllumRequirements req;
    OK(illum_requirements(vkGetInstanceProcAddr, instance, pd, 0, &req));
    CHECK(req.shader_int64 && req.buffer_device_address && req.scalar_block_layout, "base features");
    CHECK(req.extension_count == 0 && !req.ray_query, "the base set has no extension");
    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, NULL, 0, req.queue_family, 1, &prio};
    VkPhysicalDeviceVulkan12Features f12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    f12.bufferDeviceAddress = req.buffer_device_address;
    f12.scalarBlockLayout = req.scalar_block_layout;
    VkPhysicalDeviceFeatures2 f2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    f2.features.shaderInt64 = req.shader_int64;
    VkDeviceCreateInfo dci = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2, 0, 1, &qci, 0, NULL,
                              req.extension_count, req.extensions, NULL};
    VkDevice device;
    if (vkCreateDevice(pd, &dci, NULL, &device) != VK_SUCCESS) { fprintf(stderr, "no device\n"); return 2; }
    VkQueue queue;
    vkGetDeviceQueue(device, req.queue_family, 0, &queue);

    IllumExternalDevice ext = {vkGetInstanceProcAddr, instance, pd, device, queue, req.queue_family, 0};
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

    /* The host's storage image, readback buffer, command buffer and fence. */
    VkImageCreateInfo ii = {VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO, NULL, 0, VK_IMAGE_TYPE_2D,
        VK_FORMAT_R32G32B32A32_SFLOAT, {W, H, 1}, 1, 1, VK_SAMPLE_COUNT_1_BIT, VK_IMAGE_TILING_OPTIMAL,
        VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_SHARING_MODE_EXCLUSIVE, 0, NULL,
        VK_IMAGE_LAYOUT_UNDEFINED};
    VkImage image;
    VK(vkCreateImage(device, &ii, NULL, &image));
    VkMemoryRequirements mr;
    vkGetImageMemoryRequirements(device, image, &mr);
    VkMemoryAllocateInfo mai = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, NULL, mr.size,
        memory_type(pd, mr.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)};
    VkDeviceMemory image_memory, buffer_memory;
    VK(vkAllocateMemory(device, &mai, NULL, &image_memory));
    VK(vkBindImageMemory(device, image, image_memory, 0));
    VkImageViewCreateInfo vi = {VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO, NULL, 0, image, VK_IMAGE_VIEW_TYPE_2D,
        VK_FORMAT_R32G32B32A32_SFLOAT, {0}, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    VkImageView view;
    VK(vkCreateImageView(device, &vi, NULL, &view));
    VkBufferCreateInfo bi = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, NULL, 0, W * H * 16,
        VK_BUFFER_USAGE_TRANSFER_DST_BIT, VK_SHARING_MODE_EXCLUSIVE, 0, NULL};
    VkBuffer readback;
    VK(vkCreateBuffer(device, &bi, NULL, &readback));
    vkGetBufferMemoryRequirements(device, readback, &mr);
    mai.allocationSize = mr.size;
    mai.memoryTypeIndex = memory_type(pd, mr.memoryTypeBits,
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    VK(vkAllocateMemory(device, &mai, NULL, &buffer_memory));
    VK(vkBindBufferMemory(device, readback, buffer_memory, 0));
    VkCommandPoolCreateInfo pci = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, NULL, 0, req.queue_family};
    VkCommandPool pool;
    VK(vkCreateCommandPool(device, &pci, NULL, &pool));
    VkCommandBufferAllocateInfo cai = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, NULL, pool,
        VK_COMMAND_BUFFER_LEVEL_PRIMARY, 1};
    VkCommandBuffer cmd;
    VK(vkAllocateCommandBuffers(device, &cai, &cmd));

    /* One pass of SPP samples into the host's image, copied out in the same command buffer. */
    IllumTarget target = {image, view, W, H,
        VK_IMAGE_LAYOUT_UNDEFINED, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
        VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT};
    IllumSession *session = NULL;
    OK(illum_session_create(ctx, prepared, scene, SEED, &target, &session));
    VkCommandBufferBeginInfo cbi = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, NULL,
        VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT, NULL};
    VK(vkBeginCommandBuffer(cmd, &cbi));
    OK(illum_session_record_pass(session, cmd, 0, SPP));
    VkBufferImageCopy copy = {0, 0, 0, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1}, {0, 0, 0}, {W, H, 1}};
    vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback, 1, &copy);
    VkMemoryBarrier to_host = {VK_STRUCTURE_TYPE_MEMORY_BARRIER, NULL, VK_ACCESS_TRANSFER_WRITE_BIT,
        VK_ACCESS_HOST_READ_BIT};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0,
        NULL, 0, NULL);
    VK(vkEndCommandBuffer(cmd));
    VkFenceCreateInfo fci = {VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    VK(vkCreateFence(device, &fci, NULL, &fence));
    VkSubmitInfo si = {VK_STRUCTURE_TYPE_SUBMIT_INFO, NULL, 0, NULL, NULL, 1, &cmd, 0, NULL};
    VK(vkQueueSubmit(queue, 1, &si, fence));
    VK(vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX));
    float *texels;
    VK(vkMapMemory(device, buffer_memory, 0, W * H * 16, 0, (void **)&texels));
    int differing = 0;
    for (int i = 0; i < W * H; i++) {
        if (memcmp(&texels[4 * i], &reference[3 * i], 12) != 0 || texels[4 * i + 3] != 1.0f) differing++;
    }
    CHECK(differing == 0, "%d pixels of the recorded pass differ from the blocking render", differing);
    vkUnmapMemory(device, buffer_memory);
    illum_session_destroy(session);

    illum_prepared_destroy(prepared);
    illum_scene_destroy(scene);
    illum_context_destroy(ctx);
    /* The device is still the host's. */
    vkDestroyFence(device, fence, NULL);
    vkDestroyCommandPool(device, pool, NULL);
    vkDestroyBuffer(device, readback, NULL);
    vkDestroyImageView(device, view, NULL);
    vkDestroyImage(device, image, NULL);
    vkFreeMemory(device, buffer_memory, NULL);
    vkFreeMemory(device, image_memory, NULL);
    vkDestroyDevice(device, NULL);
    destroy_messenger(instance, messenger, NULL);
    vkDestroyInstance(instance, NULL);
    CHECK(validation_messages == 0, "%d validation messages", validation_messages);
    if (failures) { fprintf(stderr, "%d check(s) failed\n", failures); return 1; }
    printf("capi: ok\n");
    return 0;
}
