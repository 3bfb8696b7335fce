/* The Vulkan side of a C host embedding illum, shared by examples/embed.c and
 * tests/capi/embed_test.c: an instance (optionally with validation and synchronization
 * validation, counting their messages), a device created with what illum_requirements asks for,
 * storage images for illum with read-back buffers, and one command buffer and fence. Plain C11;
 * every function is static (one program per file that includes it). */
#ifndef ILLUM_EMBED_HOST_H
#define ILLUM_EMBED_HOST_H

#include "illum.h"

#include <stdio.h>
#include <string.h>

typedef struct {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice pd;
    VkDevice device;
    VkQueue queue;
    uint32_t family;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    IllumRequirements req;
} Host;

/* A storage image for illum (R32G32B32A32_SFLOAT) and a host-visible buffer it is copied to. */
typedef struct {
    VkImage image;
    VkImageView view;
    VkDeviceMemory memory;
    VkBuffer readback;
    VkDeviceMemory readback_memory;
    uint32_t width, height;
} HostImage;

/* Validation messages seen so far (with validation on). */
static int host_validation_messages = 0;

static VKAPI_ATTR VkBool32 VKAPI_CALL host_on_message(
    VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT types,
    const VkDebugUtilsMessengerCallbackDataEXT *data, void *user) {
    (void)severity; (void)types; (void)user;
    fprintf(stderr, "[validation] %s\n", data->pMessage);
    host_validation_messages++;
    return VK_FALSE;
}

static uint32_t host_memory_type(const Host *h, uint32_t bits, VkMemoryPropertyFlags want) {
    VkPhysicalDeviceMemoryProperties p;
    vkGetPhysicalDeviceMemoryProperties(h->pd, &p);
    for (uint32_t i = 0; i < p.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (p.memoryTypes[i].propertyFlags & want) == want) return i;
    return 0;
}

/* Instance (validation when `validation`), the first physical device, and a device with illum's
 * base requirements. Returns 0, or non-zero with a message on stderr. */
static int host_create(Host *h, int validation) {
    memset(h, 0, sizeof *h);
    const char *layers[] = {"VK_LAYER_KHRONOS_validation"};
    const char *exts[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
    VkValidationFeaturesEXT features = {VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, NULL, 1, &sync, 0, NULL};
    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO, NULL, "illum C host", 1, NULL, 0,
                             VK_API_VERSION_1_2};
    VkInstanceCreateInfo ici = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, validation ? &features : NULL, 0,
                                &app, validation ? 1 : 0, layers, validation ? 1 : 0, exts};
    if (vkCreateInstance(&ici, NULL, &h->instance) != VK_SUCCESS) {
        fprintf(stderr, "host: no Vulkan instance\n");
        return 1;
    }
    if (validation) {
        PFN_vkCreateDebugUtilsMessengerEXT create_messenger =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(h->instance, "vkCreateDebugUtilsMessengerEXT");
        VkDebugUtilsMessengerCreateInfoEXT mci = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT, NULL, 0,
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
            host_on_message, NULL};
        if (create_messenger(h->instance, &mci, NULL, &h->messenger) != VK_SUCCESS) return 1;
    }
    uint32_t n = 1;
    if (vkEnumeratePhysicalDevices(h->instance, &n, &h->pd) < 0 || n == 0) {
        fprintf(stderr, "host: no physical device\n");
        return 1;
    }
    /* What illum needs, asked; a device created with exactly that. */
    if (illum_requirements(vkGetInstanceProcAddr, h->instance, h->pd, 0, &h->req) != ILLUM_STATUS_OK) {
        fprintf(stderr, "host: %s\n", illum_last_error());
        return 1;
    }
    const IllumRequirements *r = &h->req;
    h->family = r->queue_family;
    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, NULL, 0, h->family, 1, &prio};
    VkPhysicalDeviceVulkan12Features f12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    f12.bufferDeviceAddress = r->buffer_device_address;
    f12.scalarBlockLayout = r->scalar_block_layout;
    VkPhysicalDeviceFeatures2 f2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    f2.features.shaderInt64 = r->shader_int64;
    VkDeviceCreateInfo dci = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2, 0, 1, &qci, 0, NULL,
                              r->extension_count, r->extensions, NULL};
    if (vkCreateDevice(h->pd, &dci, NULL, &h->device) != VK_SUCCESS) {
        fprintf(stderr, "host: no device\n");
        return 1;
    }
    vkGetDeviceQueue(h->device, h->family, 0, &h->queue);
    VkCommandPoolCreateInfo pci = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, NULL,
                                   VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, h->family};
    VkCommandBufferAllocateInfo cai = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, NULL, VK_NULL_HANDLE,
                                       VK_COMMAND_BUFFER_LEVEL_PRIMARY, 1};
    VkFenceCreateInfo fci = {VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if (vkCreateCommandPool(h->device, &pci, NULL, &h->pool) != VK_SUCCESS) return 1;
    cai.commandPool = h->pool;
    if (vkAllocateCommandBuffers(h->device, &cai, &h->cmd) != VK_SUCCESS) return 1;
    if (vkCreateFence(h->device, &fci, NULL, &h->fence) != VK_SUCCESS) return 1;
    return 0;
}

/* illum's view of the host's device (its context is created from this). */
static IllumExternalDevice host_external(const Host *h) {
    IllumExternalDevice ext = {vkGetInstanceProcAddr, h->instance, h->pd, h->device, h->queue, h->family, 0};
    return ext;
}

static int host_image_create(const Host *h, HostImage *im, uint32_t width, uint32_t height) {
    memset(im, 0, sizeof *im);
    im->width = width;
    im->height = height;
    VkImageCreateInfo ii = {VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO, NULL, 0, VK_IMAGE_TYPE_2D,
        VK_FORMAT_R32G32B32A32_SFLOAT, {width, height, 1}, 1, 1, VK_SAMPLE_COUNT_1_BIT, VK_IMAGE_TILING_OPTIMAL,
        VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_SHARING_MODE_EXCLUSIVE, 0, NULL,
        VK_IMAGE_LAYOUT_UNDEFINED};
    if (vkCreateImage(h->device, &ii, NULL, &im->image) != VK_SUCCESS) return 1;
    VkMemoryRequirements mr;
    vkGetImageMemoryRequirements(h->device, im->image, &mr);
    VkMemoryAllocateInfo mai = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, NULL, mr.size,
        host_memory_type(h, mr.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)};
    if (vkAllocateMemory(h->device, &mai, NULL, &im->memory) != VK_SUCCESS) return 1;
    if (vkBindImageMemory(h->device, im->image, im->memory, 0) != VK_SUCCESS) return 1;
    VkImageViewCreateInfo vi = {VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO, NULL, 0, im->image,
        VK_IMAGE_VIEW_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT, {0}, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    if (vkCreateImageView(h->device, &vi, NULL, &im->view) != VK_SUCCESS) return 1;
    VkBufferCreateInfo bi = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, NULL, 0, (VkDeviceSize)width * height * 16,
        VK_BUFFER_USAGE_TRANSFER_DST_BIT, VK_SHARING_MODE_EXCLUSIVE, 0, NULL};
    if (vkCreateBuffer(h->device, &bi, NULL, &im->readback) != VK_SUCCESS) return 1;
    vkGetBufferMemoryRequirements(h->device, im->readback, &mr);
    mai.allocationSize = mr.size;
    mai.memoryTypeIndex = host_memory_type(h, mr.memoryTypeBits,
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    if (vkAllocateMemory(h->device, &mai, NULL, &im->readback_memory) != VK_SUCCESS) return 1;
    return vkBindBufferMemory(h->device, im->readback, im->readback_memory, 0) != VK_SUCCESS;
}

/* The image as this host uses it: discarded before each pass, copied after. */
static IllumTarget host_image_target(const HostImage *im) {
    IllumTarget t = {im->image, im->view, im->width, im->height,
        VK_IMAGE_LAYOUT_UNDEFINED, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
        VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT};
    return t;
}

/* Starts recording the host's command buffer. */
static VkCommandBuffer host_begin(const Host *h) {
    VkCommandBufferBeginInfo cbi = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, NULL,
                                    VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT, NULL};
    vkResetCommandBuffer(h->cmd, 0);
    vkBeginCommandBuffer(h->cmd, &cbi);
    return h->cmd;
}

/* Copies `count` images to their read-back buffers, submits and waits. Returns 0 on success. */
static int host_end_and_wait(const Host *h, const HostImage *images, int count) {
    for (int k = 0; k < count; k++) {
        const HostImage *im = &images[k];
        VkBufferImageCopy copy = {0, 0, 0, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1}, {0, 0, 0},
                                  {im->width, im->height, 1}};
        vkCmdCopyImageToBuffer(h->cmd, im->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, im->readback, 1, &copy);
    }
    VkMemoryBarrier to_host = {VK_STRUCTURE_TYPE_MEMORY_BARRIER, NULL, VK_ACCESS_TRANSFER_WRITE_BIT,
                               VK_ACCESS_HOST_READ_BIT};
    vkCmdPipelineBarrier(h->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0,
                         NULL, 0, NULL);
    if (vkEndCommandBuffer(h->cmd) != VK_SUCCESS) return 1;
    VkSubmitInfo si = {VK_STRUCTURE_TYPE_SUBMIT_INFO, NULL, 0, NULL, NULL, 1, &h->cmd, 0, NULL};
    if (vkQueueSubmit(h->queue, 1, &si, h->fence) != VK_SUCCESS) return 1;
    if (vkWaitForFences(h->device, 1, &h->fence, VK_TRUE, UINT64_MAX) != VK_SUCCESS) return 1;
    return vkResetFences(h->device, 1, &h->fence) != VK_SUCCESS;
}

/* Copies the image's last read-back (RGBA floats, row-major) into `rgba`. */
static int host_image_read(const Host *h, const HostImage *im, float *rgba) {
    void *p;
    size_t bytes = (size_t)im->width * im->height * 16;
    if (vkMapMemory(h->device, im->readback_memory, 0, bytes, 0, &p) != VK_SUCCESS) return 1;
    memcpy(rgba, p, bytes);
    vkUnmapMemory(h->device, im->readback_memory);
    return 0;
}

static void host_image_destroy(const Host *h, HostImage *im) {
    vkDestroyBuffer(h->device, im->readback, NULL);
    vkFreeMemory(h->device, im->readback_memory, NULL);
    vkDestroyImageView(h->device, im->view, NULL);
    vkDestroyImage(h->device, im->image, NULL);
    vkFreeMemory(h->device, im->memory, NULL);
}

/* Destroys the device and instance (illum's context must be gone). */
static void host_destroy(Host *h) {
    vkDestroyFence(h->device, h->fence, NULL);
    vkDestroyCommandPool(h->device, h->pool, NULL);
    vkDestroyDevice(h->device, NULL);
    if (h->messenger != VK_NULL_HANDLE) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger =
            (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(h->instance, "vkDestroyDebugUtilsMessengerEXT");
        destroy_messenger(h->instance, h->messenger, NULL);
    }
    vkDestroyInstance(h->instance, NULL);
}

#endif
