/* test_multipart.c - the daemon's multipart/form-data parser
 * (server/multipart.c): the boundary of a Content-Type, the parts of curl's
 * and a browser's bodies, and every malformed body refused with a reason;
 * then its fuzz seeds and crashes replayed. */
#include "multipart.h"
#include "testio.h"
#include "testlib.h"

/* the fuzz target itself, replayed on its seeds and crashes below */
#include "../fuzz/fuzz_multipart.c"

#include <string.h>

#define CURL_BODY                                                                        \
    "--------------------------d74496d66958873e\r\n"                                     \
    "Content-Disposition: form-data; name=\"xdmf\"; filename=\"m.xdmf\"\r\n"             \
    "Content-Type: application/octet-stream\r\n"                                         \
    "\r\n"                                                                               \
    "<Xdmf>\r\n</Xdmf>\r\n"                                                              \
    "--------------------------d74496d66958873e\r\n"                                     \
    "Content-Disposition: form-data; name=\"h5\"; filename=\"m.h5\"\r\n"                 \
    "\r\n"                                                                               \
    "\x89HDF\r\n\x1a\n\0\0\r\n"                                                          \
    "--------------------------d74496d66958873e--\r\n"
#define CURL_B "------------------------d74496d66958873e"

TEST(boundary_of_content_type)
{
    char b[MP_BOUNDARY_MAX + 1];

    ASSERT_EQ_INT(mp_boundary("multipart/form-data; boundary=" CURL_B, b), 0);
    ASSERT_TRUE(!strcmp(b, CURL_B));
    ASSERT_EQ_INT(mp_boundary("Multipart/Form-Data;charset=x;BOUNDARY=\"a b\"", b), 0);
    ASSERT_TRUE(!strcmp(b, "a b"));
    ASSERT_EQ_INT(mp_boundary("multipart/form-data; name=\"x;y\"; boundary=z", b), 0);
    ASSERT_TRUE(!strcmp(b, "z"));
    ASSERT_EQ_INT(mp_boundary("multipart/mixed; boundary=z", b), -1);
    ASSERT_EQ_INT(mp_boundary("multipart/form-data", b), -1);
    ASSERT_EQ_INT(mp_boundary("multipart/form-data; boundary=", b), -1);
    ASSERT_EQ_INT(mp_boundary("multipart/form-data; boundary=\"open", b), -1);
    ASSERT_EQ_INT(mp_boundary("multipart/form-data; boundary=a<b", b), -1);
    ASSERT_EQ_INT(mp_boundary("multipart/form-data; boundary=\"ends \"", b), -1);
    /* 70 characters at most */
    char ct[200] = "multipart/form-data; boundary=";
    memset(ct + strlen(ct), 'a', 70);
    ASSERT_EQ_INT(mp_boundary(ct, b), 0);
    ASSERT_EQ_INT((int)strlen(b), 70);
    strcat(ct, "a");
    ASSERT_EQ_INT(mp_boundary(ct, b), -1);
    ASSERT_EQ_INT(mp_boundary(NULL, b), -1);
}

TEST(curl_body)
{
    static const char body[] = CURL_BODY;
    mp_part p[4];
    char why[200] = "";
    int n;

    ASSERT_EQ_INT(mp_parse(body, sizeof body - 1, CURL_B, p, 4, &n, why, sizeof why), 0);
    ASSERT_EQ_INT(n, 2);
    ASSERT_TRUE(!strcmp(p[0].name, "xdmf") && !strcmp(p[0].filename, "m.xdmf"));
    ASSERT_EQ_INT((int)p[0].len, 15);
    ASSERT_TRUE(!memcmp(body + p[0].off, "<Xdmf>\r\n</Xdmf>", 15));
    ASSERT_TRUE(!strcmp(p[1].name, "h5") && !strcmp(p[1].filename, "m.h5"));
    ASSERT_EQ_INT((int)p[1].len, 10); /* NUL bytes and CRLF inside a file are data */
    ASSERT_TRUE(!memcmp(body + p[1].off, "\x89HDF\r\n\x1a\n\0\0", 10));
    /* a preamble and an epilogue are ignored; an empty part is one */
    static const char b2[] = "hello\r\n--q\r\nContent-Disposition: form-data; "
                             "name=\"a\"\r\n\r\n\r\n--q--\r\nbye";
    ASSERT_EQ_INT(mp_parse(b2, sizeof b2 - 1, "q", p, 4, &n, why, sizeof why), 0);
    ASSERT_EQ_INT(n, 1);
    ASSERT_EQ_INT((int)p[0].len, 0);
    ASSERT_TRUE(!strcmp(p[0].filename, ""));
}

/* body b (NUL-terminated) with boundary "q" refused, its reason holding
 * the text want */
static int refused(const char *b, const char *want)
{
    mp_part p[2];
    char why[200] = "";
    int n;

    if (mp_parse(b, strlen(b), "q", p, 2, &n, why, sizeof why) != -1) {
        printf("  accepted: %s\n", b);
        return 0;
    }
    if (!strstr(why, want)) {
        printf("  reason '%s', not '%s'\n", why, want);
        return 0;
    }
    return 1;
}

#define CD "Content-Disposition: form-data; "

TEST(malformed_bodies)
{
    ASSERT_TRUE(refused("", "does not hold the boundary"));
    ASSERT_TRUE(refused("--x\r\n", "does not hold the boundary"));
    ASSERT_TRUE(refused("--q", "not ended by CRLF"));
    ASSERT_TRUE(
        refused("--q\r\n" CD "name=\"a\"\r\n\r\ndata", "not ended by the boundary"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\"\r\n", "not ended by a blank line"));
    ASSERT_TRUE(refused("--q\r\n\r\nx\r\n--q--", "no Content-Disposition"));
    ASSERT_TRUE(
        refused("--q\r\nContent-Type: x\r\n\r\nx\r\n--q--", "no Content-Disposition"));
    ASSERT_TRUE(
        refused("--q\r\nContent-Disposition: attachment; name=\"a\"\r\n\r\n\r\n--q--",
                "not form-data"));
    ASSERT_TRUE(refused("--q\r\n" CD "filename=\"a\"\r\n\r\n\r\n--q--", "no name"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"\"\r\n\r\n\r\n--q--", "no name"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=a\r\n\r\n\r\n--q--", "malformed"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\r\n\r\n\r\n--q--", "malformed"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\"; filename=\"x\r\n\r\n\r\n--q--",
                        "malformed or too long filename"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\"\r\n" CD "name=\"b\"\r\n\r\n\r\n--q--",
                        "two Content-Disposition"));
    ASSERT_TRUE(refused("--q\r\nno colon\r\n\r\n\r\n--q--", "no name"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\x01\"\r\n\r\n\r\n--q--", "control byte"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\"\r\n\r\n\r\n--qX", "not ended by CRLF"));
    ASSERT_TRUE(refused("--q\r\n" CD "name=\"a\"\r\n\r\n\r\n--q\r\n" CD
                        "name=\"b\"\r\n\r\n\r\n--q\r\n" CD "name=\"c\"\r\n\r\n\r\n--q--",
                        "more than 2 parts"));
    /* a NUL in a header (the body itself is binary and may hold them) */
    static const char nul[] = "--q\r\n" CD "name=\"a\0\"\r\n\r\n\r\n--q--";
    mp_part p[2];
    char why[200] = "";
    int n;
    ASSERT_EQ_INT(mp_parse(nul, sizeof nul - 1, "q", p, 2, &n, why, sizeof why), -1);
    ASSERT_TRUE(strstr(why, "control byte") != NULL);
    /* a name longer than the part's field */
    char big[400];
    snprintf(big, sizeof big, "--q\r\n" CD "name=\"%0100d\"\r\n\r\n\r\n--q--", 7);
    ASSERT_TRUE(refused(big, "too long"));
    /* a header block longer than MP_HEADERS_MAX */
    size_t hl = MP_HEADERS_MAX + 100;
    char *h = malloc(hl + 64);
    ASSERT_TRUE(h != NULL);
    strcpy(h, "--q\r\nX-Pad: ");
    memset(h + strlen(h), 'p', MP_HEADERS_MAX);
    strcpy(h + 11 + MP_HEADERS_MAX, "\r\n\r\n\r\n--q--");
    ASSERT_TRUE(refused(h, "too long"));
    free(h);
}

static int replay_multipart(const char *buf, size_t len)
{
    return LLVMFuzzerTestOneInput((const uint8_t *)buf, len); /* aborts on a bug */
}

TEST(fuzz_replay)
{
    int n, bad = replay_fuzz("multipart", replay_multipart, &n);

    printf("  # %d fuzz inputs replayed\n", n);
    ASSERT_TRUE(n > 0);
    ASSERT_EQ_INT(bad, 0);
}

TEST_MAIN("multipart", T(boundary_of_content_type), T(curl_body), T(malformed_bodies),
          T(fuzz_replay))
