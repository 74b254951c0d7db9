#!/usr/bin/env python3
"""Tests of the fallback preprocessor funitproc.py (standard library unittest; run by ctest).

Each bad input must be rejected with its file:line, and the transformation must keep the
line numbers of the .pf file.
"""
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import funitproc  # noqa: E402


class PreprocessorTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def write(self, name, text):
        path = os.path.join(self.tmp.name, name)
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(textwrap.dedent(text).lstrip("\n"))
        return path

    def run_tool(self, *args):
        return subprocess.run([sys.executable, os.path.join(HERE, "funitproc.py"), *args],
                              capture_output=True, text=True, check=False)

    def assert_rejected(self, name, text, line, fragment):
        path = self.write(name, text)
        out = os.path.join(self.tmp.name, "out.F90")
        proc = self.run_tool("preprocess", path, out)
        self.assertNotEqual(proc.returncode, 0, proc.stderr)
        self.assertIn(f"{name}:{line}:", proc.stderr)
        self.assertIn(fragment, proc.stderr)
        self.assertFalse(os.path.exists(out))

    def test_assert_keeps_line_numbers(self):
        path = self.write("test_a.pf", """
            module test_a
              use funit
              implicit none
            contains
              @test
              subroutine test_x()
                @assertEqual(1, 1, message='it''s fine!') ! trailing comment
                @assertEqual(1, &
                     ! a comment line inside
                     1)
              end subroutine test_x
            end module test_a
            """)
        out = os.path.join(self.tmp.name, "test_a.F90")
        proc = self.run_tool("preprocess", path, out)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(out, encoding="utf-8") as handle:
            lines = handle.read().split("\n")
        self.assertTrue(lines[0].startswith('# 1 "'))
        body = lines[1:]                           # body[k] is line k+1 of the .pf
        self.assertEqual(body[4].strip(), "!@test")
        self.assertEqual(
            body[6].strip(),
            "call assertEqual(1, 1, message='it''s fine!', location=SourceLocation('test_a.pf', 7));"
            " if (anyExceptions()) return ! trailing comment")
        self.assertEqual(body[7].strip(), "call assertEqual(1, &")
        self.assertEqual(body[9].strip(),
                         "1, location=SourceLocation('test_a.pf', 8)); if (anyExceptions()) return")
        self.assertEqual(body[10].strip(), "end subroutine test_x")

    def test_module_name_must_match_file(self):
        self.assert_rejected("test_b.pf", """
            module test_other
              use funit
            contains
              @test
              subroutine test_x()
              end subroutine test_x
            end module test_other
            """, 1, "must be named like the file")

    def test_unknown_directive(self):
        self.assert_rejected("test_c.pf", """
            module test_c
              use funit
            contains
              @testcase
              subroutine test_x()
              end subroutine test_x
            end module test_c
            """, 4, "unsupported directive")

    def test_test_with_arguments(self):
        self.assert_rejected("test_d.pf", """
            module test_d
              use funit
            contains
              @test
              subroutine test_x(n)
                integer, intent(in) :: n
              end subroutine test_x
            end module test_d
            """, 5, "must take no arguments")

    def test_directive_without_subroutine(self):
        self.assert_rejected("test_e.pf", """
            module test_e
              use funit
            contains
              @test
              function test_x() result(r)
                integer :: r
                r = 1
              end function test_x
            end module test_e
            """, 5, "must be followed by a subroutine")

    def test_reserved_name(self):
        self.assert_rejected("test_f.pf", """
            module test_f
              use funit
            contains
              @test
              subroutine suite()
              end subroutine suite
            end module test_f
            """, 5, "reserved")

    def test_mpitest_needs_npes(self):
        self.assert_rejected("test_g.pf", """
            module test_g
              use funit
              use pfunit
            contains
              @mpitest
              subroutine test_x(this)
                class(MpiTestMethod), intent(inout) :: this
              end subroutine test_x
            end module test_g
            """, 5, "npes")

    def test_unterminated_assert(self):
        self.assert_rejected("test_h.pf", """
            module test_h
              use funit
            contains
              @test
              subroutine test_x()
                @assertTrue(.true.
              end subroutine test_x
            end module test_h
            """, 6, "must end with ')'")

    def test_no_tests(self):
        self.assert_rejected("test_i.pf", """
            module test_i
              use funit
            end module test_i
            """, 1, "no @test")

    def test_mpitest_in_serial_driver(self):
        path = self.write("test_j.pf", """
            module test_j
              use funit
              use pfunit
            contains
              @mpitest(npes=[1, 2])
              subroutine test_x(this)
                class(MpiTestMethod), intent(inout) :: this
              end subroutine test_x
            end module test_j
            """)
        out = os.path.join(self.tmp.name, "drv.F90")
        proc = self.run_tool("driver", "--name", "t", "-o", out, path)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("MPI_PES", proc.stderr)
        proc = self.run_tool("driver", "--mpi", "--name", "t", "-o", out, path)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(out, encoding="utf-8") as handle:
            self.assertIn("call pfunit_run_mpi_test('test_j', 'test_x', pf1_t1, [1, 2])",
                          handle.read())

    def test_npes_larger_than_mpi_pes(self):
        path = self.write("test_k.pf", """
            module test_k
              use funit
              use pfunit
            contains
              @mpitest(npes=[4])
              subroutine test_x(this)
                class(MpiTestMethod), intent(inout) :: this
              end subroutine test_x
            end module test_k
            """)
        out = os.path.join(self.tmp.name, "drv.F90")
        proc = self.run_tool("driver", "--mpi", "--np", "2", "--name", "t", "-o", out, path)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("test_k.pf:6:", proc.stderr)
        self.assertIn("raise MPI_PES", proc.stderr)

    def test_options(self):
        self.assertEqual(funitproc.parse_options("npes=[1, 3], ifdef=FOO"),
                         {"npes": [1, 3], "ifdef": "FOO"})
        self.assertEqual(funitproc.split_comment("a = '!' ! c"), ("a = '!' ", "! c"))


if __name__ == "__main__":
    unittest.main()
