/* Preloaded into the sanitizer test run (tools/run-tests.sh): dlclose() does
 * nothing, so shared libraries stay mapped until exit.
 *
 * Why: the Vulkan loader unloads the driver (lavapipe) when an instance is
 * destroyed. LeakSanitizer runs at exit and no longer sees the driver's global
 * variables, so every block they still point to is reported as a leak from an
 * "<unknown module>" that no suppression can name. Keeping libraries mapped
 * makes those blocks reachable again, and a real leak in a library is then
 * reported with the library's name. (Later Vulkan loaders offer the same with
 * VK_LOADER_DISABLE_DYNAMIC_LIBRARY_UNLOADING; Debian 12's 1.3.239 does not.) */
int dlclose(void *handle);

int dlclose(void *handle)
{
    (void)handle;
    return 0;
}
