;;;; The README's recipes as a test: every ```lisp and ```sh block of README.md, verbatim, in the
;;;; order of the page. Lisp blocks are typed into a fresh SBCL REPL (its standard input), without
;;;; the Makefile's CL_SOURCE_REGISTRY; a block starting with (require :asdf) starts a new REPL,
;;;; the others continue the previous one. Sh blocks run in bash from the checkout. Blocks before
;;;; "## With ROS" run without a ROS master; from there on a private roscore (a free port, its own
;;;; ROS_HOME) runs, and a block whose command is roslaunch is started in the background, as in
;;;; the terminal of its own the page asks for, replacing the previous launch. Prints
;;;; "README recipes: K/N blocks"; a block counts only when it ran to its end without an error.

(in-package :cram-plans-tests-ros)

(def-suite readme :in cram-plans-tests:all
  :description "The README's lisp and sh blocks, verbatim.")

(in-suite readme)

(defparameter *readme-inputs* '(("(interaction)" . "1 1"))
  "What the user types after a form of a block: (form-text . input), the input following the
line holding the form (interaction reads the answers from the REPL's standard input).")

(defparameter *readme-expected* '(("(interaction)" . "There is your product!"))
  "What the output of a lisp block holding a form must show: (form-text . text). The README says
the interaction finds the product and points at it.")

(defparameter *readme-block-seconds* 900 "Time allowed for one block.")

(defstruct readme-block index language text section)

(defun readme-blocks (&optional (file (repo-file "README.md")))
  "The ```lisp and ```sh blocks of FILE in order, each with the ## heading it is under."
  (let ((blocks '()) (section "") (language nil) (lines '()) (index 0))
    (with-open-file (in file)
      (loop for line = (read-line in nil nil)
            while line
            do (cond (language
                      (if (uiop:string-prefix-p "```" line)
                          (progn (push (make-readme-block
                                        :index (incf index) :language language :section section
                                        :text (format nil "~{~a~%~}" (reverse lines)))
                                       blocks)
                                 (setf language nil lines '()))
                          (push line lines)))
                     ((uiop:string-prefix-p "## " line) (setf section (subseq line 3)))
                     ((member line '("```lisp" "```sh") :test #'string=)
                      (setf language (if (string= line "```lisp") :lisp :sh))))))
    (nreverse blocks)))

(defun with-user-input (text)
  "TEXT with the *README-INPUTS* answers inserted after the lines holding their forms."
  (with-output-to-string (out)
    (dolist (line (uiop:split-string (string-right-trim '(#\Newline) text) :separator '(#\Newline)))
      (write-line line out)
      (dolist (entry *readme-inputs*)
        (when (search (car entry) line) (write-line (cdr entry) out))))))

(defun readme-environment (&optional (base (sb-ext:posix-environ)))
  "BASE without CL_SOURCE_REGISTRY, with CRAM_PLANS_README_TEST=1."
  (cons "CRAM_PLANS_README_TEST=1"
        (remove-if (lambda (e) (or (uiop:string-prefix-p "CL_SOURCE_REGISTRY=" e)
                                   (uiop:string-prefix-p "CRAM_PLANS_README_TEST=" e)))
                   base)))

(defun tail (text &optional (n 2500))
  (if (> (length text) n) (subseq text (- (length text) n)) text))

(defstruct readme-run
  (env nil) (dir nil) (work nil) (session nil) (session-log nil) (launch nil) (results '()))

(defun make-scratch-checkout (dir)
  "A directory in DIR holding a symbolic link to every entry of the checkout but out/, so that
the blocks, run there, write what they make (out/run, out/runs.jsonl ...) into DIR instead of
the checkout's out/, which belongs to the user; its namestring."
  (let* ((checkout (asdf:system-source-directory "cram-plans"))
         (work (uiop:ensure-directory-pathname (merge-pathnames "checkout/" dir))))
    (ensure-directories-exist work)
    (dolist (entry (append (uiop:directory-files checkout) (uiop:subdirectories checkout)))
      (let ((name (if (uiop:directory-pathname-p entry)
                      (car (last (pathname-directory entry)))
                      (file-namestring entry))))
        (unless (string= name "out")
          (sb-posix:symlink (string-right-trim "/" (namestring entry))
                            (concatenate 'string (namestring work) name)))))
    (namestring work)))

(defun remove-scratch-links (work)
  "Unlink the links MAKE-SCRATCH-CHECKOUT made in WORK (never what they point to)."
  (let ((checkout (asdf:system-source-directory "cram-plans")))
    (dolist (entry (append (uiop:directory-files checkout) (uiop:subdirectories checkout)))
      (let* ((name (if (uiop:directory-pathname-p entry)
                       (car (last (pathname-directory entry)))
                       (file-namestring entry)))
             (link (concatenate 'string work name)))
        (when (ignore-errors (sb-posix:s-islnk (sb-posix:stat-mode (sb-posix:lstat link))))
          (sb-posix:unlink link))))))

(defun readme-start (run name program args &key input)
  "Start PROGRAM in the run's scratch copy of the checkout (see MAKE-SCRATCH-CHECKOUT), output
to NAME.log in the run's directory; the process (and its log path)."
  (let* ((log (format nil "~a~a.log" (readme-run-dir run) name))
         (p (sb-ext:run-program program args :search t :wait nil
                                             :directory (readme-run-work run)
                                             :environment (readme-run-env run)
                                             :input (if input :stream nil)
                                             :output log :if-output-exists :supersede :error :output)))
    (when *ros* (push p (private-ros-processes *ros*)))
    (values p log)))

(defun file-text (path) (if (probe-file path) (uiop:read-file-string path) ""))

(defun end-session (run)
  "Close the REPL's input and wait for it to exit (stopping it after 30 s)."
  (let ((p (readme-run-session run)))
    (when p
      (ignore-errors (close (sb-ext:process-input p)))
      (unless (wait-until 30 (lambda () (not (sb-ext:process-alive-p p))))
        (stop-process p))
      (when *ros* (setf (private-ros-processes *ros*) (remove p (private-ros-processes *ros*))))
      (setf (readme-run-session run) nil))))

(defun run-lisp-block (run block)
  "Type BLOCK into the current REPL (a new one when it starts with (require :asdf)); (values ok
detail)."
  (let ((text (readme-block-text block))
        (marker (format nil "README-BLOCK-OK ~d" (readme-block-index block))))
    (when (or (null (readme-run-session run))
              (uiop:string-prefix-p "(require :asdf)" (string-left-trim '(#\Space #\Newline) text)))
      (end-session run)
      (multiple-value-bind (p log)
          (readme-start run (format nil "repl-~d" (readme-block-index block)) "sbcl"
                        '("--noinform" "--no-userinit" "--no-sysinit" "--disable-debugger")
                        :input t)
        (setf (readme-run-session run) p (readme-run-session-log run) log)))
    (let* ((p (readme-run-session run))
           (log (readme-run-session-log run))
           (start (length (file-text log))))
      (handler-case
          (let ((in (sb-ext:process-input p)))
            (write-string (with-user-input text) in)
            (format in "~%(cl:format cl:t \"~~&~a~~%\")~%(cl:finish-output)~%" marker)
            (finish-output in))
        (error (e) (return-from run-lisp-block (values nil (format nil "the REPL is gone: ~a" e)))))
      (wait-until *readme-block-seconds*
                  (lambda () (or (search marker (file-text log) :start2 start)
                                 (not (sb-ext:process-alive-p p))))
                  0.2)
      (let* ((out (file-text log))
             (own (subseq out (min start (length out))))
             (ended (search marker own))
             (missing (loop for (form . expected) in *readme-expected*
                            when (and (search form text) (not (search expected own)))
                              collect expected)))
        (unless ended (end-session run))
        (values (and ended (null missing))
                (format nil "~@[the output lacks ~{~s~^, ~}~%~]~a" missing (tail own)))))))

(defun launch-block-p (block)
  (and (eq :sh (readme-block-language block))
       (uiop:string-prefix-p "roslaunch " (string-left-trim " " (readme-block-text block)))))

(defun launch-block-nodes (block)
  "The nodes whose start shows that BLOCK's launch is up: the map server, and the simulated robot
for launch/sim_robot.launch."
  (cons "/map_server"
        (and (search "sim_robot.launch" (readme-block-text block)) (list "/sim_robot"))))

(defun run-launch-block (run block)
  "Start the roslaunch of BLOCK in the background, replacing the previous launch; ok when its
nodes come up (LAUNCH-BLOCK-NODES)."
  (let ((old (readme-run-launch run)))
    (when old
      (stop-process old)
      (setf (private-ros-processes *ros*) (remove old (private-ros-processes *ros*)))))
  (multiple-value-bind (p log)
      (readme-start run (format nil "launch-~d" (readme-block-index block)) "bash"
                    (list "-c" (readme-block-text block)))
    (setf (readme-run-launch run) p)
    (let ((ok (wait-until 60 (lambda () (and (sb-ext:process-alive-p p)
                                             (let ((nodes (rosnode-list)))
                                               (every (lambda (node) (member node nodes :test #'string=))
                                                      (launch-block-nodes block)))))
                          0.5)))
      (values ok (tail (file-text log))))))

(defun run-sh-block (run block)
  "Run BLOCK with bash -e in the scratch copy of the checkout; ok when it exits 0."
  (multiple-value-bind (p log)
      (readme-start run (format nil "sh-~d" (readme-block-index block)) "bash"
                    (list "-e" "-c" (readme-block-text block)))
    (unless (wait-until *readme-block-seconds* (lambda () (not (sb-ext:process-alive-p p))) 0.2)
      (stop-process p))
    (when *ros* (setf (private-ros-processes *ros*) (remove p (private-ros-processes *ros*))))
    (values (eql 0 (sb-ext:process-exit-code p)) (tail (file-text log)))))

(defun run-readme-block (run block)
  (multiple-value-bind (ok detail)
      (handler-case (cond ((eq :lisp (readme-block-language block)) (run-lisp-block run block))
                          ((launch-block-p block) (run-launch-block run block))
                          (t (run-sh-block run block)))
        (error (e) (values nil (format nil "the test could not run it: ~a" e))))
    (push (list block (and ok t) detail) (readme-run-results run))
    (format t "~&  README block ~d (~a, ~(~a~)): ~:[FAILED~;ok~]~%" (readme-block-index block)
            (readme-block-section block) (readme-block-language block) ok)
    ok))

(defun fresh-repl-block-p (block)
  (and block (eq :lisp (readme-block-language block))
       (uiop:string-prefix-p "(require :asdf)"
                             (string-left-trim '(#\Space #\Newline) (readme-block-text block)))))

(defun run-readme-blocks (run blocks)
  "Run BLOCKS in order. A REPL is quit before a launch that a fresh REPL follows, as a user
starting over does (its node would otherwise go on publishing its belief state's TF)."
  (loop for (block next) on blocks
        do (when (and (launch-block-p block) (fresh-repl-block-p next))
             (end-session run))
           (run-readme-block run block)))

(test readme-recipes
  (let* ((blocks (readme-blocks))
         (ros-from (position "With ROS" blocks :key #'readme-block-section :test #'string=))
         (dir (format nil "/tmp/cram-readme-test-~d-~d/" (sb-posix:getpid) (get-universal-time)))
         (run (make-readme-run :dir dir)))
    (ensure-directories-exist dir)
    (setf (readme-run-work run) (make-scratch-checkout dir))
    (is (>= (length blocks) 8) "README.md has ~d lisp/sh blocks" (length blocks))
    (unwind-protect
         (progn
           ;; without a master: ROS_MASTER_URI points at a port nothing listens on
           (setf (readme-run-env run)
                 (readme-environment
                  (cons (format nil "ROS_MASTER_URI=http://127.0.0.1:~d" (free-port))
                        (remove-if (lambda (e) (uiop:string-prefix-p "ROS_MASTER_URI=" e))
                                   (sb-ext:posix-environ)))))
           (run-readme-blocks run (subseq blocks 0 (or ros-from (length blocks))))
           (end-session run)
           (when ros-from
             (let ((left (call-with-private-ros
                          (lambda ()
                            (setf (readme-run-env run) (readme-environment (private-ros-env *ros*)))
                            (run-readme-blocks run (subseq blocks ros-from))
                            (end-session run)))))
               (is (null left) "processes left running after the README's ROS blocks: ~s" left))))
      (end-session run)
      (remove-scratch-links (readme-run-work run))
      (uiop:delete-directory-tree (uiop:ensure-directory-pathname dir) :validate t
                                                                       :if-does-not-exist :ignore))
    (let* ((results (reverse (readme-run-results run)))
           (passed (count-if #'second results)))
      (format t "~&README recipes: ~d/~d blocks~%" passed (length blocks))
      (dolist (r results)
        (destructuring-bind (block ok detail) r
          (is-true ok "README block ~d (~a, ~(~a~)) failed:~%~a~%--- output ---~%~a"
                   (readme-block-index block) (readme-block-section block)
                   (readme-block-language block) (readme-block-text block) detail)))
      (is (= passed (length blocks))))))
