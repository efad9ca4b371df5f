/* The bind guard: loaded into every ROS process (LD_PRELOAD, set by this package's environment hook when
 * devel/setup.bash is sourced), it binds a server socket that asks for all interfaces to ROS_IP instead.
 *
 * Why: roscpp's XML-RPC server (the slave API: shutdown, paramUpdate, publisherUpdate, requestTopic)
 * always binds all interfaces, whatever ROS_IP says, and so do rospy, the master and roslaunch's own
 * server whenever ROS_IP is not a loopback address. Any host that reaches the computer could then stop a
 * node. ROS 1 offers no setting for it; this does it for every process, C++ and Python alike.
 *
 * Only binds to the wildcard address (0.0.0.0, ::) are changed, and only when ROS_IP is a literal IPv4
 * or IPv6 address: an IPv6 wildcard with an IPv4 ROS_IP becomes the IPv4-mapped address. Everything else
 * (a socket bound to a given address, a client's port-0 bind, Unix sockets) is passed through unchanged.
 * When ROS_IP is not an address of this host the bind fails (EADDRNOTAVAIL): closed, as ROS_IP asked.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <dlfcn.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

typedef int (*bind_function)(int, const struct sockaddr*, socklen_t);

static int real_bind(int fd, const struct sockaddr* address, socklen_t length) {
  static bind_function next = NULL;
  if (next == NULL) next = (bind_function)dlsym(RTLD_NEXT, "bind");
  if (next == NULL) {
    errno = ENOSYS;
    return -1;
  }
  return next(fd, address, length);
}

static int bind_ipv4(int fd, const struct sockaddr_in* asked, const char* ros_ip) {
  struct sockaddr_in chosen = *asked;
  if (inet_pton(AF_INET, ros_ip, &chosen.sin_addr) != 1) return real_bind(fd, (const struct sockaddr*)asked, sizeof(*asked));
  return real_bind(fd, (const struct sockaddr*)&chosen, sizeof(chosen));
}

static int bind_ipv6(int fd, const struct sockaddr_in6* asked, const char* ros_ip) {
  struct sockaddr_in6 chosen = *asked;
  struct in_addr ipv4;
  if (inet_pton(AF_INET6, ros_ip, &chosen.sin6_addr) == 1) {
    return real_bind(fd, (const struct sockaddr*)&chosen, sizeof(chosen));
  }
  if (inet_pton(AF_INET, ros_ip, &ipv4) == 1) {  /* ::ffff:a.b.c.d */
    memset(&chosen.sin6_addr, 0, sizeof(chosen.sin6_addr));
    chosen.sin6_addr.s6_addr[10] = 0xff;
    chosen.sin6_addr.s6_addr[11] = 0xff;
    memcpy(&chosen.sin6_addr.s6_addr[12], &ipv4, sizeof(ipv4));
    return real_bind(fd, (const struct sockaddr*)&chosen, sizeof(chosen));
  }
  return real_bind(fd, (const struct sockaddr*)asked, sizeof(*asked));
}

int bind(int fd, const struct sockaddr* address, socklen_t length) {
  const char* ros_ip = getenv("ROS_IP");
  if (ros_ip == NULL || ros_ip[0] == '\0' || address == NULL) return real_bind(fd, address, length);
  if (address->sa_family == AF_INET && length >= (socklen_t)sizeof(struct sockaddr_in)) {
    const struct sockaddr_in* asked = (const struct sockaddr_in*)address;
    if (asked->sin_addr.s_addr == htonl(INADDR_ANY)) return bind_ipv4(fd, asked, ros_ip);
  } else if (address->sa_family == AF_INET6 && length >= (socklen_t)sizeof(struct sockaddr_in6)) {
    const struct sockaddr_in6* asked = (const struct sockaddr_in6*)address;
    if (memcmp(&asked->sin6_addr, &in6addr_any, sizeof(in6addr_any)) == 0) return bind_ipv6(fd, asked, ros_ip);
  }
  return real_bind(fd, address, length);
}
