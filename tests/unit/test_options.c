/* test_options.c - the option table (opt/options.h): strict parsing, ranges,
 * defaults that read back as themselves, --hausd's three forms. */
#include "qdc.h"
#include "testlib.h"

#include <string.h>

TEST(every_default_reads_back_as_itself)
{
    size_t n;
    const opt_desc *t = opt_table(&n);
    opt_options d, o;
    opt_defaults(&d);
    ASSERT_TRUE(n >= 18);
    for (size_t i = 0; i < n; i++) {
        char v[64];
        opt_value_text(&t[i], &d, v, sizeof v);
        opt_defaults(&o);
        memset((char *)&o + t[i].off, 0x5a,
               t[i].type == OPT_T_REAL || t[i].type == OPT_T_HAUSD ? sizeof(double)
                                                                   : sizeof(int));
        ASSERT_OK(opt_set(&o, t[i].name, v, NULL));
        ASSERT_TRUE(memcmp((char *)&o + t[i].off, (char *)&d + t[i].off,
                           t[i].type == OPT_T_REAL || t[i].type == OPT_T_HAUSD
                               ? sizeof(double)
                               : sizeof(int)) == 0);
    }
}

TEST(ranges_and_strictness)
{
    opt_options o;
    qdc_error e;
    opt_defaults(&o);
    qdc_error_clear(&e);
    ASSERT_OK(opt_set(&o, "mu", "0.25", NULL));
    ASSERT_NEAR(o.mu, 0.25, 0);
    /* mu > 0: zero, an underflow to zero, NaN, infinity and junk are refused */
    static const char *const bad_mu[] = {"0",  "1e-400", "nan", "inf", "-1",
                                         " 1", "1 ",     "1x",  "",    "1e13"};
    for (size_t i = 0; i < sizeof bad_mu / sizeof bad_mu[0]; i++) {
        ASSERT_EQ_INT(opt_set(&o, "mu", bad_mu[i], &e), QDC_EINVAL);
        ASSERT_NEAR(o.mu, 0.25, 0); /* unchanged */
    }
    ASSERT_TRUE(strstr(e.msg, "(0, 1000000000000]") != NULL);
    /* integers: digits only, inside [lo, hi] */
    ASSERT_OK(opt_set(&o, "max-iter", "25", NULL)); /* '-' and '_' alike */
    ASSERT_EQ_INT(o.max_iter, 25);
    ASSERT_EQ_INT(opt_set(&o, "max_iter", "5.0", NULL), QDC_EINVAL);
    ASSERT_EQ_INT(opt_set(&o, "max_iter", "0x5", NULL), QDC_EINVAL);
    ASSERT_EQ_INT(opt_set(&o, "max_iter", "10001", NULL), QDC_EINVAL);
    ASSERT_EQ_INT(opt_set(&o, "ls_halvings", "61", NULL), QDC_EINVAL);
    ASSERT_OK(opt_set(&o, "ls_halvings", "60", NULL));
    /* the closed end of a range is accepted, the open one not */
    ASSERT_OK(opt_set(&o, "eps_rel", "1", NULL));
    ASSERT_EQ_INT(opt_set(&o, "eps_rel", "0", NULL), QDC_EINVAL);
    ASSERT_OK(opt_set(&o, "tol_move", "0", NULL));
    /* words and booleans */
    ASSERT_OK(opt_set(&o, "boundary", "slide", NULL));
    ASSERT_EQ_INT(o.boundary, OPT_BOUNDARY_SLIDE);
    ASSERT_EQ_INT(opt_set(&o, "boundary", "Slide", NULL), QDC_EINVAL);
    ASSERT_OK(opt_set(&o, "finish", "off", NULL));
    ASSERT_EQ_INT(o.finish, 0);
    ASSERT_OK(opt_set(&o, "finish", "true", NULL));
    ASSERT_EQ_INT(o.finish, 1);
    ASSERT_EQ_INT(opt_set(&o, "finish", "2", NULL), QDC_EINVAL);
    ASSERT_EQ_INT(opt_set(&o, "no_such_option", "1", &e), QDC_EINVAL);
    ASSERT_TRUE(strstr(e.msg, "unknown option") != NULL);
}

TEST(hausd_forms)
{
    opt_options o;
    opt_defaults(&o);
    ASSERT_OK(opt_set(&o, "hausd", "0.002", NULL));
    ASSERT_NEAR(o.hausd, 0.002, 0);
    ASSERT_NEAR(o.hausd_rel, 0, 0);
    ASSERT_OK(opt_set(&o, "hausd", "0.1%", NULL));
    ASSERT_NEAR(o.hausd, 0, 0);
    ASSERT_NEAR(o.hausd_rel, 0.001, 1e-18);
    ASSERT_OK(opt_set(&o, "hausd", "rel:1e-4", NULL));
    ASSERT_NEAR(o.hausd_rel, 1e-4, 0);
    static const char *const bad[] = {"-1",  "rel:",  "rel:-1",  "%",
                                      "nan", "1e-3x", "rel:inf", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        ASSERT_EQ_INT(opt_set(&o, "hausd", bad[i], NULL), QDC_EINVAL);
    ASSERT_NEAR(o.hausd_rel, 1e-4, 0);
    {
        char v[64];
        opt_value_text(opt_find("hausd"), &o, v, sizeof v);
        ASSERT_TRUE(strcmp(v, "rel:0.0001") == 0);
    }
}

TEST_MAIN("options", T(every_default_reads_back_as_itself), T(ranges_and_strictness),
          T(hausd_forms))
