// The OIDC login's cookie check: inside the LMS's frame a browser may refuse Telelab's cookies, and the launch
// would then fail; so, framed, a test cookie is written and read back first. Kept: continue to the LMS's sign-in;
// refused: show "Open in a new window" (the login again, in a top-level window where cookies work).
const box = document.getElementById('login-check');
const continueUrl = box.dataset.continueUrl;

function cookiesWork() {
  const name = 'telelab_cookie_check';
  const secure = window.location.protocol === 'https:' ? '; SameSite=None; Secure' : '';
  document.cookie = `${name}=1; path=/; max-age=60${secure}`;
  const kept = document.cookie.split(';').some((part) => part.trim().startsWith(`${name}=`));
  document.cookie = `${name}=; path=/; max-age=0${secure}`;
  return kept;
}

if (window.top === window.self || cookiesWork()) {
  window.location.replace(continueUrl);
} else {
  document.getElementById('cookies-blocked').hidden = false;
  document.getElementById('open-new-window').focus();
}
